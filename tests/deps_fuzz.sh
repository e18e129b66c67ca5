#!/bin/sh
# Makes sure clang can build libFuzzer programs (make fuzz): clang with its
# sanitizer and fuzzer runtimes (libclang_rt.fuzzer). Debian ships the
# runtimes of clang N in libclang-rt-N-dev (Debian 12, Ubuntu 23.04 on) or,
# before, in libclang-common-N-dev. Installs what is missing with apt-get when
# running as root; otherwise names the packages and fails. The unit tests
# never need any of it (make test replays the fuzz corpora without libFuzzer).
set -u
CLANG=${CLANG:-clang}

can_fuzz() {
    command -v "$CLANG" >/dev/null 2>&1 || return 1
    printf '%s\n' '#include <stddef.h>' '#include <stdint.h>' \
        'int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n) { (void)d; (void)n; return 0; }' |
        "$CLANG" -x c -fsanitize=fuzzer,address,undefined - -o /dev/null >/dev/null 2>&1
}

apt_install() {
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q "$@" </dev/null >/dev/null 2>&1 ||
        { apt-get update -q </dev/null >/dev/null 2>&1 && apt-get install -y -q "$@" </dev/null >/dev/null 2>&1; }
}

# The package holding the runtimes of the installed clang, or nothing.
runtime_package() {
    major=$("$CLANG" -dumpversion 2>/dev/null | cut -d. -f1)
    [ -n "$major" ] || return 0
    for p in "libclang-rt-$major-dev" "libclang-common-$major-dev"; do
        if apt-cache show "$p" >/dev/null 2>&1; then echo "$p"; return 0; fi
    done
}

if can_fuzz; then exit 0; fi

if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    if ! command -v "$CLANG" >/dev/null 2>&1; then
        echo "deps_fuzz: installing clang with apt-get"
        apt_install clang || { echo "deps_fuzz: apt-get could not install clang" >&2; exit 1; }
    fi
    package=$(runtime_package)
    if [ -z "$package" ]; then
        apt-get update -q </dev/null >/dev/null 2>&1
        package=$(runtime_package)
    fi
    if [ -n "$package" ]; then
        echo "deps_fuzz: installing $package (clang's fuzzer runtime) with apt-get"
        apt_install "$package" || { echo "deps_fuzz: apt-get could not install $package" >&2; exit 1; }
    fi
    if can_fuzz; then exit 0; fi
    echo "deps_fuzz: $CLANG still cannot link -fsanitize=fuzzer${package:+ after installing $package}" >&2
    exit 1
fi

echo "deps_fuzz: make fuzz needs clang and its fuzzer runtime (libclang_rt.fuzzer). Install them with:" >&2
echo "           sudo apt-get install clang libclang-rt-\$(clang -dumpversion | cut -d. -f1)-dev" >&2
echo "           (libclang-common-N-dev instead for clang 13 and older)" >&2
exit 1
