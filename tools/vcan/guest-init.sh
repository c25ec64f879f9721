#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# PID 1 of the User-Mode Linux guest of tools/vcan/with-vcan (which starts it through a
# two-line wrapper naming the host's bash). The guest's root file system is the host's "/".
# Environment (from the kernel command line): WITH_VCAN_DIR, the host's temporary folder of this
# run (cmd.sh: the command; status, guest-error, t-*: what comes back); WITH_VCAN_OUT_TTY and
# WITH_VCAN_ERR_TTY (1 when the caller's stdout/stderr is a terminal); WITH_VCAN_ROWS/COLS.
# Sets up /proc, /sys, /run, /dev/shm, lo, the CAN modules and vcan0, runs cmd.sh in its own
# session with its output on the guest consoles tty1/tty2, writes its exit status, powers off.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
d=$WITH_VCAN_DIR
umask 022

halt_guest() {
    sync
    poweroff -f >/dev/null 2>&1
    echo o >/proc/sysrq-trigger 2>/dev/null
    sleep 5
    exit 1 # PID 1 exiting makes the kernel panic, which also ends linux.uml
}
fail() {
    printf '%s\n' "$*" >>"$d/guest-error"
    printf 'with-vcan init: %s\n' "$*" >/dev/console 2>/dev/null
    halt_guest
}
step() { # step DESCRIPTION COMMAND... : run, fail with its output on error
    local what=$1
    shift
    "$@" >"$d/step.log" 2>&1 || fail "$what failed: $*: $(cat "$d/step.log")"
}
# (Each program started in the guest costs ~25 ms: few are started here.)

echo "$EPOCHREALTIME" >"$d/t-init"
step 'mounting /proc' mount -t proc proc /proc
step 'mounting /sys' mount -t sysfs sysfs /sys
step 'mounting /run' mount -t tmpfs -o mode=0755 tmpfs /run
step 'creating /dev/shm' mkdir -p /dev/shm /dev/pts /run/with-vcan/modules
step 'mounting /dev/shm' mount -t tmpfs -o mode=1777 tmpfs /dev/shm
mount -t devpts -o mode=0620,ptmxmode=0666 devpts /dev/pts >/dev/null 2>&1
ln -sf /proc/self/fd /dev/fd 2>/dev/null
ln -sf /proc/self/fd/0 /dev/stdin 2>/dev/null
ln -sf /proc/self/fd/1 /dev/stdout 2>/dev/null
ln -sf /proc/self/fd/2 /dev/stderr 2>/dev/null
read -r host_name 2>/dev/null </etc/hostname || host_name=with-vcan
echo "$host_name" >/proc/sys/kernel/hostname 2>/dev/null
step 'bringing lo up' ip link set up dev lo

m=/run/with-vcan/modules
step 'mounting the UML modules' mount -t hostfs -o /usr/lib/uml/modules hostfs "$m"
# Let modprobe find the other modules (can-gw, can-j1939) too.
[ -d /lib/modules ] && mount --bind "$m" /lib/modules >/dev/null 2>&1
read -r kv </proc/sys/kernel/osrelease
for ko in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko \
    drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
    step "loading module $ko" insmod "$m/$kv/kernel/$ko"
done
step 'creating vcan0' ip link add dev vcan0 type vcan
step 'bringing vcan0 up' ip link set up dev vcan0

# CMD's stdout/stderr: guest consoles tty1/tty2 are host fds 3/4. Raw mode
# passes bytes unchanged. When the caller's stream is not a terminal CMD gets
# a pipe (relayed by cat), as it would natively.
# Kept open here: the window size set below would be reset by a first open.
exec 7>/dev/tty1 8>/dev/tty2
step 'setting up tty1' stty -F /dev/tty1 raw -echo \
    rows "${WITH_VCAN_ROWS:-0}" cols "${WITH_VCAN_COLS:-0}"
step 'setting up tty2' stty -F /dev/tty2 raw -echo \
    rows "${WITH_VCAN_ROWS:-0}" cols "${WITH_VCAN_COLS:-0}"
relays=()
out=/dev/tty1
err=/dev/tty2
fifos=()
[ "$WITH_VCAN_OUT_TTY" = 1 ] || { out=/run/with-vcan/out; fifos+=("$out"); }
[ "$WITH_VCAN_ERR_TTY" = 1 ] || { err=/run/with-vcan/err; fifos+=("$err"); }
if [ "${#fifos[@]}" -gt 0 ]; then
    step 'creating fifos' mkfifo "${fifos[@]}"
fi
if [ "$out" != /dev/tty1 ]; then
    cat "$out" >/dev/tty1 &
    relays+=("$!")
fi
if [ "$err" != /dev/tty2 ]; then
    cat "$err" >/dev/tty2 &
    relays+=("$!")
fi

echo "$EPOCHREALTIME" >"$d/t-ready"
# Own session and process group, so leftovers can be ended afterwards.
setsid -w "$BASH" --noprofile --norc "$d/cmd.sh" \
    </dev/null >"$out" 2>"$err" 7>&- 8>&- &
cmd_pid=$!
wait "$cmd_pid"
rc=$?
echo "$EPOCHREALTIME" >"$d/t-done"
# Background processes CMD left behind would keep the relays open.
kill -KILL -- "-$cmd_pid" >/dev/null 2>&1
if [ "${#relays[@]}" -gt 0 ]; then
    ( sleep 60; kill "${relays[@]}" ) >/dev/null 2>&1 &
    watchdog=$!
    wait "${relays[@]}"
    kill "$watchdog" >/dev/null 2>&1
fi
printf '%s\n' "$rc" >"$d/status.tmp" && mv "$d/status.tmp" "$d/status"
halt_guest
