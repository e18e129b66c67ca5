/* base.h - what every examples/common header shares: EX_FN marks their
   functions static (each example is one translation unit) and tells the
   compiler an unused one is fine. */
#ifndef EXAMPLES_COMMON_BASE_H
#define EXAMPLES_COMMON_BASE_H

#if defined(__GNUC__) || defined(__clang__)
#  define EX_FN static __attribute__((unused))
#else
#  define EX_FN static
#endif

#endif /* EXAMPLES_COMMON_BASE_H */
