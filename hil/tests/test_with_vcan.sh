#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Tests for hil/with-vcan. Exits non-zero if any test fails; the last line
# printed is "N passed, N failed". Needs can-utils and python3 (and, on a
# kernel without vcan, user-mode-linux, kmod and iproute2).
set -uo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
wv=$here/../with-vcan
passed=0
failed=0
# Under /tmp: the User-Mode Linux guest sees the host's /tmp (not /run).
work=$(mktemp -d /tmp/test_with_vcan.XXXXXXXX)
trap 'rm -rf -- "$work"' EXIT

pass() {
    passed=$((passed + 1))
    printf 'PASS %s\n' "$1"
}
fail() {
    failed=$((failed + 1))
    printf 'FAIL %s\n' "$1"
    shift
    local line
    for line in "$@"; do printf '     %s\n' "$line"; done
}
# run NAME ARGS...: run with-vcan with no stdin; sets rc, out, err.
run() {
    "$wv" "$@" </dev/null >"$work/out" 2>"$work/err"
    rc=$?
    out=$(cat "$work/out")
    err=$(cat "$work/err")
}
details() { printf '%s\n' "exit status $rc" "stdout: $out" "stderr: $err"; }

# (a) vcan0 exists, is a vcan and is up.
run ip -details link show vcan0
if [[ $rc -eq 0 && $out == *vcan0* && $out =~ [[:space:]]vcan[[:space:]] && $out == *UP* ]]; then
    pass "(a) ip -details link show vcan0 shows an up vcan"
else
    mapfile -t d < <(details)
    fail "(a) ip -details link show vcan0 shows an up vcan" "${d[@]}"
fi

# (b) candump + cansend round trip in one invocation.
run bash -c 'candump -n 1 vcan0 >"$1" & sleep 0.5; cansend vcan0 123#DEADBEEF; wait; cat "$1"' \
    _ "$work/candump.txt"
if [[ $rc -eq 0 && $out =~ vcan0[[:space:]]+123[[:space:]]+\[4\][[:space:]]+DE\ AD\ BE\ EF ]]; then
    pass "(b) candump receives what cansend sent"
else
    mapfile -t d < <(details)
    fail "(b) candump receives what cansend sent" "${d[@]}"
fi

# (c) exit status propagates.
run bash -c 'exit 7'
if [[ $rc -eq 7 ]]; then
    pass "(c) exit status 7 propagates"
else
    mapfile -t d < <(details)
    fail "(c) exit status 7 propagates" "${d[@]}"
fi
run true
rc_true=$rc
run false
if [[ $rc_true -eq 0 && $rc -eq 1 ]]; then
    pass "(c) true/false give 0/1"
else
    fail "(c) true/false give 0/1" "true: $rc_true, false: $rc"
fi

# (d) stdout and stderr separate; arguments with spaces and quotes intact.
# shellcheck disable=SC2016 # (literal $ and backquotes on purpose)
args=('a b' "it's" 'say "hi"' '$HOME `x` \n' '' '  lead and trail  ' $'tab\there' '*')
run bash -c 'echo to-stdout; echo to-stderr >&2; printf "<%s>\n" "$@"' _ "${args[@]}"
expected=to-stdout$'\n'$(printf '<%s>\n' "${args[@]}")
if [[ $rc -eq 0 && $out == "$expected" && $err == to-stderr ]]; then
    pass "(d) stdout/stderr separate, arguments intact"
else
    mapfile -t d < <(details)
    fail "(d) stdout/stderr separate, arguments intact" "expected stdout: $expected" "${d[@]}"
fi

# (e) working directory preserved (with a space in it).
mkdir -p "$work/dir with space"
(cd "$work/dir with space" && "$wv" pwd </dev/null >"$work/out" 2>"$work/err")
rc=$?
out=$(cat "$work/out")
err=$(cat "$work/err")
if [[ $rc -eq 0 && $out == "$work/dir with space" ]]; then
    pass "(e) working directory preserved"
else
    mapfile -t d < <(details)
    fail "(e) working directory preserved" "${d[@]}"
fi

# (f) Python can open and bind an AF_CAN raw socket on vcan0.
run python3 -c 'import socket; s=socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW); s.bind(("vcan0",)); print("ok")'
if [[ $rc -eq 0 && $out == ok ]]; then
    pass "(f) python3 AF_CAN socket binds to vcan0"
else
    mapfile -t d < <(details)
    fail "(f) python3 AF_CAN socket binds to vcan0" "${d[@]}"
fi

# (g) the caller's environment arrives.
PMA_TEST_VALUE='x y "z"' VIRTUAL_ENV=/some/venv PYTHONPATH=/some/path \
    run bash -c 'printf "%s|%s|%s|%s\n" "$PMA_TEST_VALUE" "$VIRTUAL_ENV" "$PYTHONPATH" "$HOME"'
if [[ $rc -eq 0 && $out == "x y \"z\"|/some/venv|/some/path|$HOME" ]]; then
    pass "(g) environment (PMA_*, VIRTUAL_ENV, PYTHONPATH, HOME) arrives"
else
    mapfile -t d < <(details)
    fail "(g) environment (PMA_*, VIRTUAL_ENV, PYTHONPATH, HOME) arrives" "${d[@]}"
fi

# (h) --help, and bad settings are errors (exit 2), never a silent skip.
run --help
if [[ $rc -eq 0 && $out == *Usage:* && $out == *PMA_WITH_VCAN* ]]; then
    pass "(h) --help prints usage"
else
    mapfile -t d < <(details)
    fail "(h) --help prints usage" "${d[@]}"
fi
PMA_WITH_VCAN=bogus run true
if [[ $rc -eq 2 && $err == *PMA_WITH_VCAN* ]]; then
    pass "(h) PMA_WITH_VCAN=bogus is an error"
else
    mapfile -t d < <(details)
    fail "(h) PMA_WITH_VCAN=bogus is an error" "${d[@]}"
fi
PMA_WITH_VCAN=uml PMA_UML=/nonexistent/linux.uml run true
if [[ $rc -eq 2 && $err == *user-mode-linux* && $err == *kmod* && $err == *iproute2* ]]; then
    pass "(h) without UML: exit 2 naming the packages to install"
else
    mapfile -t d < <(details)
    fail "(h) without UML: exit 2 naming the packages to install" "${d[@]}"
fi

# (i) UML mode only: no temporary directory or linux.uml left behind, also
#     after an interrupt.
PMA_WITH_VCAN_VERBOSE=1 run true
if [[ $err == *"mode uml"* ]]; then
    dir=$(sed -n 's/.*directory \(\/tmp\/with-vcan\.[^)]*\)).*/\1/p' "$work/err" | head -n 1)
    if [[ -n $dir && ! -e $dir ]] && ! pgrep -f -- "$dir" >/dev/null; then
        pass "(i) guest directory removed, no linux.uml left"
    else
        fail "(i) guest directory removed, no linux.uml left" "directory: '$dir'" "$(pgrep -af -- "${dir:-/nonexistent}")"
    fi

    # Job control gives the background job its own SIGINT disposition
    # (a non-interactive shell would start it with SIGINT ignored).
    marker=$work/started
    set -m
    # shellcheck disable=SC2016
    PMA_WITH_VCAN_VERBOSE=1 "$wv" bash -c 'touch "$1"; sleep 300' _ "$marker" \
        </dev/null >"$work/out" 2>"$work/err" &
    job=$!
    set +m
    for _ in $(seq 1 300); do
        [[ -e $marker ]] && break
        sleep 0.1
    done
    kill -INT "$job"
    wait "$job"
    rc=$?
    dir=$(sed -n 's/.*directory \(\/tmp\/with-vcan\.[^)]*\)).*/\1/p' "$work/err" | head -n 1)
    sleep 0.5
    if [[ -e $marker && $rc -eq 130 && -n $dir && ! -e $dir ]] && ! pgrep -f -- "$dir" >/dev/null; then
        pass "(i) SIGINT stops the guest and cleans up (exit 130)"
    else
        fail "(i) SIGINT stops the guest and cleans up (exit 130)" "exit status $rc" \
            "stderr: $(cat "$work/err")" "left: $(pgrep -af -- "${dir:-/nonexistent}")"
    fi
else
    printf 'note (i): not in UML mode here, cleanup tests not applicable\n'
fi

printf '%d passed, %d failed\n' "$passed" "$failed"
[[ $failed -eq 0 ]]
