/* Linkage test, translation unit 1: the implementations of all four headers,
   each included twice to exercise the include and implementation guards. */
#define IRRVOL_IMPLEMENTATION
#define RADINTERP_IMPLEMENTATION
#define LIGHTVEC_IMPLEMENTATION
#define RENDERCACHE_IMPLEMENTATION
#include "irrvol.h"
#include "radinterp.h"
#include "lightvec.h"
#include "rendercache.h"
#include "irrvol.h"
#include "radinterp.h"
#include "lightvec.h"
#include "rendercache.h"
