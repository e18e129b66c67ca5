/* tests/test_bvh.c compiled with the SIMD kernels off: the scalar path as a
   build without SSE2 or NEON runs it (the comparison with the SIMD path is
   then the scalar path with itself; the brute force still checks it). */
#define IRRVOL_BVH_SIMD 0
#include "tests/test_bvh.c"
