#!/bin/sh
# Builds GNU binutils 2.40 for spu-elf (as, ld, objdump, readelf, nm) for the differential
# tests (tests/tests/gnu_differential.rs and gnu_ld_differential.rs), which show as ignored
# without it.
#
#   scripts/build-spu-binutils.sh [TARBALL|debian] [PREFIX]   (PREFIX: $HOME/.local/spu-binutils)
#   scripts/build-spu-binutils.sh --testsuite-only SOURCE_DIR [PREFIX]
#
# Besides the programs it installs binutils' own test sources under
# $PREFIX/share/spu-binutils-testsuite: ld's ld-spu (tests/gnu_ld_differential.rs) and gas's
# gas/{all,elf,macros} (tests/gnu_differential.rs). --testsuite-only installs just those
# from an unpacked binutils 2.40 source tree, for a prefix built before they were.
#
# TARBALL: binutils-2.40.tar.xz from ftp.gnu.org/gnu/binutils, or Debian's
# binutils_2.40.orig.tar.*. `debian` (the default) takes the tarball from Debian's
# `binutils-source` package (bookworm: 2.40-2), fetched with `apt-get download`, the only
# download. Nothing of it enters the repository.
#
# tests/build.rs finds $PREFIX/bin/spu-elf-as there (or through SPU_BINUTILS=PREFIX); run
# `cargo clean -p spu-tests` after installing so the tests see it. Needs a C compiler,
# make, flex and bison (the build regenerates binutils' lexers); about 1.5 minutes on two
# quiet cores (2026-11-27, this project's 2-core machine).
set -eu

# Copies the test sources the differential tests read from source tree $1 to prefix $2.
install_testsuite() {
    dest="$2/share/spu-binutils-testsuite"
    mkdir -p "$dest/gas"
    rm -rf "$dest/ld-spu" "$dest/gas/all" "$dest/gas/elf" "$dest/gas/macros"
    cp -R "$1/ld/testsuite/ld-spu" "$dest/"
    for dir in all elf macros; do
        cp -R "$1/gas/testsuite/gas/$dir" "$dest/gas/"
    done
    echo "installed: $dest/ld-spu (binutils' ld-spu test sources),"
    echo "           $dest/gas/{all,elf,macros} (gas's generic test sources)"
}

if [ "${1:-}" = --testsuite-only ]; then
    if [ ! -f "${2:-}/gas/testsuite/gas/all/gas.exp" ]; then
        echo "usage: $0 --testsuite-only BINUTILS-2.40-SOURCE-DIR [PREFIX]" >&2
        exit 2
    fi
    install_testsuite "$2" "${3:-$HOME/.local/spu-binutils}"
    exit 0
fi
source=${1:-debian}
prefix=${2:-$HOME/.local/spu-binutils}
for tool in cc make flex bison; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "$0: needs $tool (Debian: apt-get install flex bison build-essential)" >&2
        exit 2
    fi
done
work=$(mktemp -d "${TMPDIR:-/tmp}/spu-binutils-build.XXXXXX")
trap 'rm -rf "$work"' EXIT
if [ "$source" = debian ]; then
    (cd "$work" && apt-get download binutils-source >/dev/null 2>&1) || {
        echo "$0: apt-get download binutils-source failed (no Debian registry?); name a tarball" >&2
        exit 2
    }
    (cd "$work" && dpkg-deb -x binutils-source_*.deb deb)
    set -- "$(ls "$work"/deb/usr/src/binutils/binutils-*.tar.* | head -1)"
fi
if [ ! -f "$1" ]; then
    echo "usage: $0 [BINUTILS-2.40-TARBALL|debian] [PREFIX]" >&2
    exit 2
fi
tarball=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
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
# ld's own SPU test sources (overlays, icache, pic...) and gas's generic ones, which the
# comparisons read when present (tests/build.rs looks for them here); on this machine
# only, never committed.
install_testsuite "../$src" "$prefix"
