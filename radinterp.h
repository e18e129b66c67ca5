/* radinterp.h - v0.1.0 - radiosity with per-pixel quadratic irradiance interpolants - public domain or MIT, see end of file

   RADINTERP.H: hierarchical radiosity, ranked discontinuities and quadratic irradiance interpolants evaluated per pixel.

   STATUS

   Skeleton: this version declares the error codes and the version macros
   only. The technique itself is not implemented yet; nothing else is declared
   until it is.

   DO THIS

       #define RADINTERP_IMPLEMENTATION
       #include "radinterp.h"

   in exactly one C or C++ file; include "radinterp.h" without the define
   everywhere else.

   CONFIGURATION MACROS

       RADINTERP_STATIC          make every function static (private to one file)
       RADINTERP_API             linkage of public functions (default: extern)
       RADINTERP_MALLOC, RADINTERP_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *radinterp_result_string(radinterp_result r);   name of an error code

   PAPER

       Stephen L. Hardt, High Fidelity Radiosity Rendering at Interactive Rates, M.Eng. thesis, MIT, 1996.
*/
#ifndef RADINTERP_H
#define RADINTERP_H

#define RADINTERP_VERSION_MAJOR 0
#define RADINTERP_VERSION_MINOR 1
#define RADINTERP_VERSION_PATCH 0

#ifndef RADINTERP_API
#  ifdef RADINTERP_STATIC
#    define RADINTERP_API static
#  else
#    define RADINTERP_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum radinterp_result {
    RADINTERP_OK = 0,
    RADINTERP_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    RADINTERP_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    RADINTERP_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    RADINTERP_ERROR_VERSION,           /* serialized data has an unsupported format version */
    RADINTERP_ERROR_CANCELLED,         /* the progress callback asked to stop */
    RADINTERP_ERROR_IO                 /* a read or write callback failed */
} radinterp_result;

RADINTERP_API const char *radinterp_result_string(radinterp_result r);

#ifdef __cplusplus
}
#endif
#endif /* RADINTERP_H */

/* ------------------------------------------------------------------------ */
#if defined(RADINTERP_IMPLEMENTATION) && !defined(RADINTERP_IMPLEMENTATION_INCLUDED)
#define RADINTERP_IMPLEMENTATION_INCLUDED

#if defined(RADINTERP_MALLOC) != defined(RADINTERP_FREE)
#  error "radinterp.h: define both RADINTERP_MALLOC and RADINTERP_FREE, or neither"
#endif
#ifndef RADINTERP_MALLOC
#  include <stdlib.h>
#  define RADINTERP_MALLOC(size) malloc(size)
#  define RADINTERP_FREE(ptr) free(ptr)
#endif

RADINTERP_API const char *radinterp_result_string(radinterp_result r)
{
    switch (r) {
    case RADINTERP_OK: return "ok";
    case RADINTERP_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RADINTERP_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RADINTERP_ERROR_CORRUPT_DATA: return "corrupt data";
    case RADINTERP_ERROR_VERSION: return "unsupported format version";
    case RADINTERP_ERROR_CANCELLED: return "cancelled";
    case RADINTERP_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* RADINTERP_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 The irrvol/radinterp/lightvec/rendercache authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
------------------------------------------------------------------------------
*/
