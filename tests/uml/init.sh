#!/bin/sh
# PID 1 inside User-Mode Linux for the SocketCAN lane (started by tests/uml/runner.py).
#
# The UML kernel boots with the host's root file system (hostfs), so the checkout, its .venv and
# Python are at the same paths inside. This script brings up a real kernel SocketCAN:
#   vcan0  virtual CAN, txqueuelen 1000 (as the README sets can0), no queueing discipline;
#   vcan1  a bus that behaves like a real adapter with the default txqueuelen 10: a tbf queue
#          holds 10 frames and drains 500 frames/s (64 kbit/s of 16-byte CAN skbs), so bursts get
#          ENOBUFS (errno 105) as on can0. Scaled down from 1 Mbit/s (about 8,000 frames/s)
#          because a process inside UML sends only about 1,500 frames/s: the bus must stay
#          slower than the sender, as a real bus is slower than a real host;
# raises the socket receive buffers (16 MiB: with the default, a reader that falls behind loses
# frames silently), runs "$UML_JOB/job.sh", writes its output and exit status to $UML_JOB, and
# powers off (PID 1 must not exit: the kernel would panic).
#
# UML_JOB (the job's directory) and UML_MODULES (the kernel's module tree, .../modules/VERSION/kernel:
# the system's under /usr/lib/uml or Debian sid's unpacked in the user's cache) come from the kernel
# command line (unknown key=value parameters become init's environment). The first line of
# $UML_JOB/setup.log says PID 1 ran (the runner's sign that the kernel booted); set-up failures are
# written there too and give exit status 125.
#
# vcan's default MTU is CAN FD's (72) on UML 6.1 but CAN XL's (2060) on Debian sid's UML 7.x:
# both buses are set to 72 (CAN FD) so the lane sees the same interfaces on every kernel; the tbf
# burst is one whole MTU (72 bytes; the kernel warns when a tbf burst is below the MTU).

PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
HOME=/root
LANG=C.UTF-8
export PATH HOME LANG
J="$UML_JOB"

finish() {
    echo "$1" > "$J/rc"
    sync
    poweroff -f
    echo o > /proc/sysrq-trigger
    sleep 10
}

fail() {
    echo "uml-init: $*" >> "$J/setup.log"
    finish 125
}

[ -d "$J" ] || { echo "uml-init: UML_JOB not set or missing: '$J'"; poweroff -f; }
echo "uml-init: started as PID $$ (kernel $(uname -r))" > "$J/setup.log"
mount -t proc proc /proc || fail "mount /proc failed"
mount -t sysfs sysfs /sys || fail "mount /sys failed"
mount -t tmpfs -o size=256m tmpfs /dev/shm 2>/dev/null
ip link set lo up || fail "ip link set lo up failed"

M="${UML_MODULES:-/usr/lib/uml/modules/$(uname -r)/kernel}"
# order matters: can-dev before vcan ("Unknown symbol can_dropped_invalid_skb"); can-bcm for
# python-can's send_periodic (errno 93 without it); sch_tbf for vcan1's adapter-like queue
for m in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko drivers/net/can/dev/can-dev.ko \
         drivers/net/can/vcan.ko net/sched/sch_tbf.ko; do
    insmod "$M/$m" >> "$J/setup.log" 2>&1 || fail "insmod $M/$m failed (kernel $(uname -r))"
done
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 txqueuelen 1000 && ip link set up vcan0 \
    || fail "cannot create vcan0"
ip link add dev vcan1 type vcan && ip link set vcan1 mtu 72 txqueuelen 10 && ip link set up vcan1 \
    && tc qdisc add dev vcan1 root tbf rate 64kbit burst 72 limit 160 \
    || fail "cannot create vcan1 with a 10-frame queue"
# net.core.rmem_max / rmem_default = 16 MiB (written directly: no procps needed)
echo 16777216 > /proc/sys/net/core/rmem_max && echo 16777216 > /proc/sys/net/core/rmem_default \
    || fail "cannot raise net.core.rmem_default/rmem_max"
echo "uml-init: SocketCAN ready (kernel $(uname -r))" >> "$J/setup.log"

sh "$J/job.sh" > "$J/output.txt" 2>&1
finish $?
