#!/bin/sh
# Makes Assimp available when it can: the examples read every format it reads
# (glTF, FBX, Collada, IFC, PLY, ...) and tests/assimp_*.c run when Debian's
# libassimp-dev is present. Optional: without it the examples read OBJ and
# those tests are left out, so this never fails. Installs it with apt-get when
# running as root, each apt-get step bounded to two minutes (machines without a
# network must not wait long for an optional package).
set -u
CC=${CC:-cc}
package="libassimp-dev"

have_assimp() { printf '#include <assimp/cimport.h>\nint main(void){return aiGetVersionMajor() == 0;}\n' | "$CC" -x c - -o /dev/null -lassimp >/dev/null 2>&1; }

if have_assimp; then exit 0; fi

if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "deps: installing $package with apt-get (optional: other formats than OBJ in the examples)"
    export DEBIAN_FRONTEND=noninteractive
    timeout 120 apt-get install -y -q $package </dev/null >/dev/null 2>&1 ||
        { timeout 120 apt-get update -q </dev/null >/dev/null 2>&1 && timeout 120 apt-get install -y -q $package </dev/null >/dev/null 2>&1; }
    if have_assimp; then exit 0; fi
fi

echo "deps: Assimp not available: the examples read OBJ only and the Assimp tests are skipped" >&2
echo "      (sudo apt-get install $package, then make, for glTF, FBX, Collada, IFC, PLY, ...)" >&2
exit 0
