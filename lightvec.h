/* lightvec.h - v0.1.0 - cached 5D indirect light vectors - public domain or MIT, see end of file

   LIGHTVEC.H: cached indirect light vectors over position and direction for interactive glossy global illumination.

   STATUS

   Skeleton: this version declares the error codes and the version macros
   only. The technique itself is not implemented yet; nothing else is declared
   until it is.

   DO THIS

       #define LIGHTVEC_IMPLEMENTATION
       #include "lightvec.h"

   in exactly one C or C++ file; include "lightvec.h" without the define
   everywhere else.

   CONFIGURATION MACROS

       LIGHTVEC_STATIC          make every function static (private to one file)
       LIGHTVEC_API             linkage of public functions (default: extern)
       LIGHTVEC_MALLOC, LIGHTVEC_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *lightvec_result_string(lightvec_result r);   name of an error code

   PAPER

       Rodolphe Crespin and Bernard Peroche, Light Vectors for a Moving Observer, WSCG 2004.
*/
#ifndef LIGHTVEC_H
#define LIGHTVEC_H

#define LIGHTVEC_VERSION_MAJOR 0
#define LIGHTVEC_VERSION_MINOR 1
#define LIGHTVEC_VERSION_PATCH 0

#ifndef LIGHTVEC_API
#  ifdef LIGHTVEC_STATIC
#    define LIGHTVEC_API static
#  else
#    define LIGHTVEC_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum lightvec_result {
    LIGHTVEC_OK = 0,
    LIGHTVEC_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    LIGHTVEC_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    LIGHTVEC_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    LIGHTVEC_ERROR_VERSION,           /* serialized data has an unsupported format version */
    LIGHTVEC_ERROR_CANCELLED,         /* the progress callback asked to stop */
    LIGHTVEC_ERROR_IO                 /* a read or write callback failed */
} lightvec_result;

LIGHTVEC_API const char *lightvec_result_string(lightvec_result r);

#ifdef __cplusplus
}
#endif
#endif /* LIGHTVEC_H */

/* ------------------------------------------------------------------------ */
#if defined(LIGHTVEC_IMPLEMENTATION) && !defined(LIGHTVEC_IMPLEMENTATION_INCLUDED)
#define LIGHTVEC_IMPLEMENTATION_INCLUDED

#if defined(LIGHTVEC_MALLOC) != defined(LIGHTVEC_FREE)
#  error "lightvec.h: define both LIGHTVEC_MALLOC and LIGHTVEC_FREE, or neither"
#endif
#ifndef LIGHTVEC_MALLOC
#  include <stdlib.h>
#  define LIGHTVEC_MALLOC(size) malloc(size)
#  define LIGHTVEC_FREE(ptr) free(ptr)
#endif

LIGHTVEC_API const char *lightvec_result_string(lightvec_result r)
{
    switch (r) {
    case LIGHTVEC_OK: return "ok";
    case LIGHTVEC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case LIGHTVEC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case LIGHTVEC_ERROR_CORRUPT_DATA: return "corrupt data";
    case LIGHTVEC_ERROR_VERSION: return "unsupported format version";
    case LIGHTVEC_ERROR_CANCELLED: return "cancelled";
    case LIGHTVEC_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* LIGHTVEC_IMPLEMENTATION */

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
