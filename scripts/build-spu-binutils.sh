#!/bin/sh
# Builds GNU binutils for spu-elf (as, ld, objdump, readelf) from Debian's binutils source
# package, for the differential tests (tests/tests/gnu_differential.rs), which show as ignored
# without it. Usage: scripts/build-spu-binutils.sh [PREFIX]   (default: $HOME/.local/spu-binutils)
# Needs root for the deb-src entry; a few minutes on two cores.
set -eu
prefix=${1:-$HOME/.local/spu-binutils}
work=${TMPDIR:-/tmp}/spu-binutils-build
if [ ! -f /etc/apt/sources.list.d/spu-binutils-src.sources ]; then
    . /etc/os-release
    cat > /etc/apt/sources.list.d/spu-binutils-src.sources <<SRC
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: $VERSION_CODENAME
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
    apt-get update -qq
fi
mkdir -p "$work"
cd "$work"
[ -d binutils-*/ ] 2>/dev/null || apt-get source --download-only binutils >/dev/null
src=$(ls -d binutils-*/ 2>/dev/null | head -1)
if [ -z "$src" ]; then
    tarball=$(ls binutils_*.orig.tar.* | head -1)
    tar xf "$tarball"
    src=$(ls -d binutils-*/ | head -1)
fi
# Debian's orig tarball may hold the upstream tarball itself.
if [ -f "$src"/binutils-*.tar.* ] 2>/dev/null; then
    (cd "$src" && tar xf binutils-*.tar.*)
    src=$(ls -d "$src"/binutils-*/ | head -1)
fi
mkdir -p build
cd build
"../$src/configure" --target=spu-elf --prefix="$prefix" --disable-nls --disable-werror \
    --disable-gdb --disable-gdbserver --disable-sim --disable-gprofng --disable-gold \
    --without-zstd >/dev/null
make -j2 MAKEINFO=true all-gas all-ld all-binutils >/dev/null
make MAKEINFO=true install-gas install-ld install-binutils >/dev/null
echo "installed: $prefix/bin/spu-elf-as"
