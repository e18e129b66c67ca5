/* The BVH tests with the SIMD kernels where the compiler offers them (SSE2,
   NEON): see tests/test_bvh.h. */
#include "tests/test_bvh.h"
