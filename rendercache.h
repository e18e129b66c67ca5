/* rendercache.h - v0.1.0 - render cache and range-image walkthroughs - public domain or MIT, see end of file

   RENDERCACHE.H: an image-space point cache that reprojects and resamples, and range-image walkthroughs of animated scenes.

   STATUS

   Skeleton: this version declares the error codes and the version macros
   only. The technique itself is not implemented yet; nothing else is declared
   until it is.

   DO THIS

       #define RENDERCACHE_IMPLEMENTATION
       #include "rendercache.h"

   in exactly one C or C++ file; include "rendercache.h" without the define
   everywhere else.

   CONFIGURATION MACROS

       RENDERCACHE_STATIC          make every function static (private to one file)
       RENDERCACHE_API             linkage of public functions (default: extern)
       RENDERCACHE_MALLOC, RENDERCACHE_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *rendercache_result_string(rendercache_result r);   name of an error code

   PAPER

       Bruce Walter, George Drettakis and Steven Parker, Interactive Rendering using the Render Cache, EGWR 1999; Nimeroff, Dorsey and Rushmeier, Implementation and Analysis of an Image-Based Global Illumination Framework for Animated Environments, IEEE TVCG 2(4), 1996.
*/
#ifndef RENDERCACHE_H
#define RENDERCACHE_H

#define RENDERCACHE_VERSION_MAJOR 0
#define RENDERCACHE_VERSION_MINOR 1
#define RENDERCACHE_VERSION_PATCH 0

#ifndef RENDERCACHE_API
#  ifdef RENDERCACHE_STATIC
#    define RENDERCACHE_API static
#  else
#    define RENDERCACHE_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum rendercache_result {
    RENDERCACHE_OK = 0,
    RENDERCACHE_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    RENDERCACHE_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    RENDERCACHE_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    RENDERCACHE_ERROR_VERSION,           /* serialized data has an unsupported format version */
    RENDERCACHE_ERROR_CANCELLED,         /* the progress callback asked to stop */
    RENDERCACHE_ERROR_IO                 /* a read or write callback failed */
} rendercache_result;

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r);

#ifdef __cplusplus
}
#endif
#endif /* RENDERCACHE_H */

/* ------------------------------------------------------------------------ */
#if defined(RENDERCACHE_IMPLEMENTATION) && !defined(RENDERCACHE_IMPLEMENTATION_INCLUDED)
#define RENDERCACHE_IMPLEMENTATION_INCLUDED

#if defined(RENDERCACHE_MALLOC) != defined(RENDERCACHE_FREE)
#  error "rendercache.h: define both RENDERCACHE_MALLOC and RENDERCACHE_FREE, or neither"
#endif
#ifndef RENDERCACHE_MALLOC
#  include <stdlib.h>
#  define RENDERCACHE_MALLOC(size) malloc(size)
#  define RENDERCACHE_FREE(ptr) free(ptr)
#endif

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r)
{
    switch (r) {
    case RENDERCACHE_OK: return "ok";
    case RENDERCACHE_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RENDERCACHE_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RENDERCACHE_ERROR_CORRUPT_DATA: return "corrupt data";
    case RENDERCACHE_ERROR_VERSION: return "unsupported format version";
    case RENDERCACHE_ERROR_CANCELLED: return "cancelled";
    case RENDERCACHE_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* RENDERCACHE_IMPLEMENTATION */

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
