#!/bin/sh
# Makes sure the reference libraries the tests use are present: Embree 3
# (ray casting ground truth) and OpenEXR 3 (reference images). The headers never
# need them. Installs them with apt-get when running as root; otherwise names the
# packages to install and fails.
set -u
CC=${CC:-cc}
packages="libembree-dev libopenexr-dev pkg-config"

have_embree() { printf '#include <embree3/rtcore.h>\nint main(void){return 0;}\n' | "$CC" -x c - -o /dev/null -lembree3 >/dev/null 2>&1; }
have_openexr() { command -v pkg-config >/dev/null 2>&1 && pkg-config --exists OpenEXR; }

# Optional: glslangValidator compiles irrvol.h's GLSL evaluator in the tests
# (without it a C transliteration checks the same text).
if ! command -v glslangValidator >/dev/null 2>&1 && [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q glslang-tools </dev/null >/dev/null 2>&1 ||
        echo "deps: glslang-tools not installed (optional: the GLSL test compiles it as C only)"
fi

if have_embree && have_openexr; then exit 0; fi

if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "deps: installing $packages with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q $packages </dev/null >/dev/null 2>&1 ||
        { apt-get update -q </dev/null >/dev/null 2>&1 && apt-get install -y -q $packages </dev/null; } ||
        { echo "deps: apt-get could not install: $packages" >&2; exit 1; }
    if have_embree && have_openexr; then exit 0; fi
    echo "deps: installed $packages but still cannot build against them" >&2
    exit 1
fi

echo "deps: the reference tests need Embree 3 and OpenEXR 3. Install them with:" >&2
echo "      sudo apt-get install $packages" >&2
exit 1
