/* tests/test_bvh.h compiled with the SIMD kernels off: the scalar path as a
   build without SSE2 or NEON runs it (the comparison with the SIMD path is
   then the scalar path with itself; the brute force still checks it). */
#define IRRVOL_BVH_SIMD 0
#define LIGHTVEC_BVH_SIMD 0
#define RADINTERP_BVH_SIMD 0
#include "tests/test_bvh.h"
