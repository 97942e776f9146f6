#!/bin/sh
# Builds GNU binutils 2.40 for spu-elf (as, ld, objdump, readelf) from its source tarball,
# for the differential tests (tests/tests/gnu_differential.rs), which show as ignored
# without it. Nothing is downloaded: name a tarball you have (binutils-2.40.tar.xz from
# ftp.gnu.org/gnu/binutils, or Debian's binutils_2.40.orig.tar.*).
#
#   scripts/build-spu-binutils.sh TARBALL [PREFIX]   (PREFIX: $HOME/.local/spu-binutils)
#
# tests/build.rs finds $PREFIX/bin/spu-elf-as there (or through SPU_BINUTILS=PREFIX); run
# `cargo clean -p spu-tests` after installing so the tests see it. Needs a C compiler,
# make and the usual build tools (no bison or flex for a release tarball); a few minutes on
# two cores.
# Untested on the project's build machine (it has no binutils source and no network).
set -eu
if [ $# -lt 1 ] || [ ! -f "$1" ]; then
    echo "usage: $0 BINUTILS-2.40-TARBALL [PREFIX]" >&2
    exit 2
fi
tarball=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
prefix=${2:-$HOME/.local/spu-binutils}
work=$(mktemp -d "${TMPDIR:-/tmp}/spu-binutils-build.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work"
tar xf "$tarball"
src=$(ls -d binutils-*/ | head -1)
# Debian's orig tarball may hold the upstream tarball itself.
if [ -z "$(ls "$src"/configure 2>/dev/null)" ] && ls "$src"/binutils-*.tar.* >/dev/null 2>&1; then
    (cd "$src" && tar xf binutils-*.tar.*)
    src=$(ls -d "$src"/binutils-*/ | head -1)
fi
case "$src" in
*2.40*) ;;
*) echo "warning: $src is not binutils 2.40; the tests compare with 2.40" >&2 ;;
esac
mkdir build
cd build
"../$src/configure" --target=spu-elf --prefix="$prefix" --disable-nls --disable-werror \
    --disable-gdb --disable-gdbserver --disable-sim --disable-gprofng --disable-gold \
    --without-zstd >/dev/null
make -j"$(nproc 2>/dev/null || echo 2)" MAKEINFO=true all-gas all-ld all-binutils >/dev/null
make MAKEINFO=true install-gas install-ld install-binutils >/dev/null
echo "installed: $prefix/bin/spu-elf-as (and spu-elf-ld, spu-elf-objdump, spu-elf-readelf)"
