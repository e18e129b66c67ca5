/* irrvol.h - v0.1.0 - irradiance volume for lighting moving objects - public domain or MIT, see end of file

   IRRVOL.H: a bilevel grid of directional irradiance samples that lights moving objects by interpolation.

   STATUS

   Skeleton: this version declares the error codes and the version macros
   only. The technique itself is not implemented yet; nothing else is declared
   until it is.

   DO THIS

       #define IRRVOL_IMPLEMENTATION
       #include "irrvol.h"

   in exactly one C or C++ file; include "irrvol.h" without the define
   everywhere else.

   CONFIGURATION MACROS

       IRRVOL_STATIC          make every function static (private to one file)
       IRRVOL_API             linkage of public functions (default: extern)
       IRRVOL_MALLOC, IRRVOL_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *irrvol_result_string(irrvol_result r);   name of an error code

   PAPER

       Gene S. Greger, The Irradiance Volume, M.S. thesis, Cornell University, 1996.
*/
#ifndef IRRVOL_H
#define IRRVOL_H

#define IRRVOL_VERSION_MAJOR 0
#define IRRVOL_VERSION_MINOR 1
#define IRRVOL_VERSION_PATCH 0

#ifndef IRRVOL_API
#  ifdef IRRVOL_STATIC
#    define IRRVOL_API static
#  else
#    define IRRVOL_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum irrvol_result {
    IRRVOL_OK = 0,
    IRRVOL_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    IRRVOL_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    IRRVOL_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    IRRVOL_ERROR_VERSION,           /* serialized data has an unsupported format version */
    IRRVOL_ERROR_CANCELLED,         /* the progress callback asked to stop */
    IRRVOL_ERROR_IO                 /* a read or write callback failed */
} irrvol_result;

IRRVOL_API const char *irrvol_result_string(irrvol_result r);

#ifdef __cplusplus
}
#endif
#endif /* IRRVOL_H */

/* ------------------------------------------------------------------------ */
#if defined(IRRVOL_IMPLEMENTATION) && !defined(IRRVOL_IMPLEMENTATION_INCLUDED)
#define IRRVOL_IMPLEMENTATION_INCLUDED

#if defined(IRRVOL_MALLOC) != defined(IRRVOL_FREE)
#  error "irrvol.h: define both IRRVOL_MALLOC and IRRVOL_FREE, or neither"
#endif
#ifndef IRRVOL_MALLOC
#  include <stdlib.h>
#  define IRRVOL_MALLOC(size) malloc(size)
#  define IRRVOL_FREE(ptr) free(ptr)
#endif

IRRVOL_API const char *irrvol_result_string(irrvol_result r)
{
    switch (r) {
    case IRRVOL_OK: return "ok";
    case IRRVOL_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case IRRVOL_ERROR_OUT_OF_MEMORY: return "out of memory";
    case IRRVOL_ERROR_CORRUPT_DATA: return "corrupt data";
    case IRRVOL_ERROR_VERSION: return "unsupported format version";
    case IRRVOL_ERROR_CANCELLED: return "cancelled";
    case IRRVOL_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* IRRVOL_IMPLEMENTATION */

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
