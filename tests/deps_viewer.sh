#!/bin/sh
# Makes sure what the interactive viewer (examples/viewer.c) and its test
# need is present: SDL2 (libsdl2-dev) to build the viewer, Xvfb (xvfb, with
# xvfb-run) to run it without a display. Installs them with apt-get when
# running as root; otherwise says what to install. Never fails: without
# SDL2 the viewer is not built, without Xvfb its test says it skipped.
set -u
packages="libsdl2-dev xvfb"

have_sdl2() { command -v sdl2-config >/dev/null 2>&1; }
have_xvfb() { command -v xvfb-run >/dev/null 2>&1; }

if have_sdl2 && have_xvfb; then exit 0; fi

if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "deps: installing $packages with apt-get (the interactive viewer)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q $packages </dev/null >/dev/null 2>&1 ||
        { apt-get update -q </dev/null >/dev/null 2>&1 && apt-get install -y -q $packages </dev/null >/dev/null 2>&1; } ||
        echo "deps: apt-get could not install $packages: the viewer is not built or not tested" >&2
    exit 0
fi

echo "deps: the interactive viewer needs SDL2 and its test Xvfb; install them with:" >&2
echo "      sudo apt-get install $packages" >&2
exit 0
