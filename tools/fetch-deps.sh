#!/usr/bin/env bash
# Fetch the third-party sources the ARM (cross) builds need into .deps/.
#
#   cmocka 1.1.5  Debian bookworm source package -> .deps/cmocka-1.1.5
#                 (cross-compiled by cmake/PmaTest.cmake as the static library `cmocka_cross`)
#
# Idempotent: does nothing when the sources are already unpacked. Works on a fresh Debian 12
# machine as root: if no deb-src entry for bookworm is configured it writes
# /etc/apt/sources.list.d/pma-src.sources and runs `apt-get update`.
# Host builds do not need this (they use Debian's libcmocka-dev).
#
# Environment: PMA_DEPS_DIR overrides the destination (default: <repo>/.deps), like the CMake
# cache variable of the same name.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
DEPS=${PMA_DEPS_DIR:-$ROOT/.deps}
CMOCKA_VERSION=1.1.5
CMOCKA_DIR=$DEPS/cmocka-$CMOCKA_VERSION
SRC_LIST=/etc/apt/sources.list.d/pma-src.sources

say() { printf 'fetch-deps: %s\n' "$*"; }
die() { printf 'fetch-deps: error: %s\n' "$*" >&2; exit 1; }

if [[ -f $CMOCKA_DIR/src/cmocka.c && -f $CMOCKA_DIR/include/cmocka.h ]]; then
    say "cmocka $CMOCKA_VERSION already unpacked at $CMOCKA_DIR: nothing to do"
    exit 0
fi

command -v apt-get >/dev/null || die "apt-get not found (this script expects Debian 12 / bookworm)"

# Is a deb-src entry for bookworm configured? Ask apt itself (it parses both the one-line and the
# deb822 formats); --no-release-info lists entries whose index files are not downloaded yet.
have_bookworm_src() {
    apt-get indextargets --no-release-info --format '$(TARGET_OF) $(RELEASE)' 2>/dev/null \
        | grep -qx 'deb-src bookworm'
}

need_update=0
if have_bookworm_src; then
    say "a deb-src entry for bookworm is configured"
else
    [[ $(id -u) -eq 0 ]] || die "no deb-src entry for bookworm is configured and I am not root: run me as root, or add one"
    say "no deb-src entry for bookworm: writing $SRC_LIST"
    cat >"$SRC_LIST" <<'EOF'
Types: deb-src
URIs: http://deb.debian.org/debian
Suites: bookworm
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    need_update=1
fi

# The entry may be configured while its Sources index was never downloaded.
if [[ $need_update -eq 0 ]] && ! apt-cache showsrc cmocka 2>/dev/null | grep -q "^Version: $CMOCKA_VERSION-"; then
    say "the Sources index does not list cmocka $CMOCKA_VERSION yet"
    need_update=1
fi
if [[ $need_update -eq 1 ]]; then
    [[ $(id -u) -eq 0 ]] || die "apt-get update is needed and I am not root"
    say "running apt-get update"
    apt-get update -q
fi

mkdir -p "$DEPS"
cd "$DEPS"

shopt -s nullglob
dscs=(cmocka_"$CMOCKA_VERSION"-*.dsc)
if [[ ${#dscs[@]} -eq 0 ]]; then
    say "downloading the cmocka source package (bookworm) into $DEPS"
    # apt-get checks the files against the signed Release/Sources indexes.
    apt-get source --download-only -q cmocka/bookworm
    dscs=(cmocka_"$CMOCKA_VERSION"-*.dsc)
    [[ ${#dscs[@]} -gt 0 ]] || die "apt-get source did not download cmocka $CMOCKA_VERSION (got: $(ls))"
else
    say "source package already downloaded: ${dscs[0]}"
fi
dsc=${dscs[${#dscs[@]}-1]}

# Unpack into a temporary directory, then move into place, so an interrupted run leaves nothing
# half-unpacked behind.
tmp=$(mktemp -d "$DEPS/.unpack.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
if command -v dpkg-source >/dev/null; then
    say "unpacking $dsc with dpkg-source (applies the Debian patches)"
    dpkg-source -q -x "$dsc" "$tmp/cmocka-$CMOCKA_VERSION"
else
    say "dpkg-source not found: unpacking $dsc with tar and applying debian/patches with patch"
    orig=(cmocka_"$CMOCKA_VERSION".orig.tar.*)
    debtar=(cmocka_"${dsc#cmocka_}")
    debtar=("${debtar[0]%.dsc}".debian.tar.*)
    [[ ${#orig[@]} -gt 0 && ${#debtar[@]} -gt 0 ]] || die "orig or debian tarball missing next to $dsc"
    mkdir "$tmp/cmocka-$CMOCKA_VERSION"
    tar -xf "${orig[0]}" -C "$tmp/cmocka-$CMOCKA_VERSION" --strip-components=1
    tar -xf "${debtar[0]}" -C "$tmp/cmocka-$CMOCKA_VERSION"
    if [[ -f $tmp/cmocka-$CMOCKA_VERSION/debian/patches/series ]]; then
        while read -r p _; do
            [[ -z $p || $p == \#* ]] && continue
            say "  applying $p"
            patch -s -p1 -d "$tmp/cmocka-$CMOCKA_VERSION" <"$tmp/cmocka-$CMOCKA_VERSION/debian/patches/$p"
        done <"$tmp/cmocka-$CMOCKA_VERSION/debian/patches/series"
    fi
fi
[[ -f $tmp/cmocka-$CMOCKA_VERSION/src/cmocka.c ]] || die "unpacked tree has no src/cmocka.c"
rm -rf "$CMOCKA_DIR"
mv "$tmp/cmocka-$CMOCKA_VERSION" "$CMOCKA_DIR"
say "cmocka $CMOCKA_VERSION ready at $CMOCKA_DIR"
