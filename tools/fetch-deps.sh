#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fetch the project's third-party C sources into .deps/, each pinned to an upstream commit and
# verified by that commit id. This is the one mechanism for third-party sources; CMake only
# checks that they are there (cmake/PmaDeps.cmake).
#
#   name             upstream                                              tag     licence
#   unity            https://github.com/ThrowTheSwitch/Unity               v2.6.1  MIT
#   cmsis_device_g4  https://github.com/STMicroelectronics/cmsis_device_g4 v1.2.4  Apache-2.0
#   cmsis_6          https://github.com/ARM-software/CMSIS_6               v6.3.0  Apache-2.0
#
# Unity is the C test framework (every C test, host and QEMU); cmsis_device_g4 (ST's
# stm32g474xx.h) and cmsis_6 (Arm's CMSIS-Core, core_cm4.h) are the board port's register
# definitions.
#
# Environment:
#   PMA_DEPS_DIR     destination (default: <repo>/.deps), like the CMake cache variable.
#   PMA_DEPS_MIRROR  a folder of git bundles unity.bundle, cmsis_device_g4.bundle,
#                    cmsis_6.bundle that hold the pinned commits, for machines without access to
#                    GitHub. Without it the sources come from GitHub.
#
# Idempotent: a source already checked out at its pinned commit is left alone; one at another
# commit (or damaged) is fetched again. A fetch goes to a temporary folder and is moved into
# place only once its commit is verified, so an interrupted run leaves nothing half-done.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
DEPS=${PMA_DEPS_DIR:-$ROOT/.deps}
MIRROR=${PMA_DEPS_MIRROR:-}

# name | upstream URL | commit (40 hex digits) | tag | licence | a file that must exist
SOURCES=(
  "unity|https://github.com/ThrowTheSwitch/Unity.git|cbcd08fa7de711053a3deec6339ee89cad5d2697|v2.6.1|MIT|src/unity.c"
  "cmsis_device_g4|https://github.com/STMicroelectronics/cmsis_device_g4.git|f4ee399953e3b5c437788526e93b10efa5fad4fa|v1.2.4|Apache-2.0|Include/stm32g474xx.h"
  "cmsis_6|https://github.com/ARM-software/CMSIS_6.git|45dab712ad84f8cbbf2b7bfc089c19088507df6f|v6.3.0|Apache-2.0|CMSIS/Core/Include/core_cm4.h"
)

say() { printf 'fetch-deps: %s\n' "$*"; }
die() { printf 'fetch-deps: error: %s\n' "$*" >&2; exit 1; }

command -v git >/dev/null || die "git not found (apt-get install git)"
export GIT_TERMINAL_PROMPT=0   # never wait for credentials: an unreachable host fails at once

if [[ -n $MIRROR && ! -d $MIRROR ]]; then
  die "PMA_DEPS_MIRROR=$MIRROR is not a folder (it names a folder of git bundles)"
fi

# checked_out DIR COMMIT FILE: true when DIR is a checkout of exactly COMMIT with FILE present
# and no local change to tracked files.
checked_out() {
  [[ -d $1/.git && -f $1/$3 ]] || return 1
  [[ $(git -C "$1" rev-parse -q --verify 'HEAD^{commit}' 2>/dev/null) == "$2" ]] || return 1
  git -C "$1" diff --quiet HEAD -- 2>/dev/null
}

mkdir -p "$DEPS"
for entry in "${SOURCES[@]}"; do
  IFS='|' read -r name url commit tag licence probe <<<"$entry"
  dest=$DEPS/$name
  if checked_out "$dest" "$commit" "$probe"; then
    say "$name $tag ($licence) at ${commit:0:12}: present"
    continue
  fi
  if [[ -n $MIRROR ]]; then
    src=$MIRROR/$name.bundle
    [[ -f $src ]] || die "PMA_DEPS_MIRROR=$MIRROR has no $name.bundle"
  else
    src=$url
  fi
  say "fetching $name $tag ($licence) at $commit from $src"
  tmp=$(mktemp -d "$DEPS/.fetch-$name.XXXXXX")
  # shellcheck disable=SC2064 # expand $tmp now: it changes with each source
  trap "rm -rf '$tmp'" EXIT
  git init -q "$tmp"
  # A bundle or a server that refuses fetches by commit: fetch every ref and tag instead.
  if ! git -C "$tmp" fetch -q --depth 1 "$src" "$commit" 2>/dev/null; then
    if ! git -C "$tmp" fetch -q --tags "$src" '+refs/heads/*:refs/remotes/src/*' 2>"$tmp.err"; then
      cat "$tmp.err" >&2; rm -f "$tmp.err"
      if [[ -z $MIRROR ]]; then
        die "cannot fetch $name from $url. Without access to GitHub, set PMA_DEPS_MIRROR to a folder of git bundles (unity.bundle, cmsis_device_g4.bundle, cmsis_6.bundle) that hold the pinned commits, e.g. PMA_DEPS_MIRROR=/path/to/vendor bash tools/fetch-deps.sh"
      fi
      die "cannot fetch $name from the bundle $src"
    fi
    rm -f "$tmp.err"
  fi
  git -C "$tmp" -c advice.detachedHead=false checkout -q "$commit" 2>/dev/null ||
    die "$src does not hold commit $commit ($name $tag)"
  got=$(git -C "$tmp" rev-parse 'HEAD^{commit}')
  [[ $got == "$commit" ]] || die "$name: checked out $got, expected $commit"
  [[ -f $tmp/$probe ]] || die "$name at $commit has no $probe"
  rm -rf "$dest"
  mv "$tmp" "$dest"
  trap - EXIT
  say "$name $tag ready at $dest"
done
