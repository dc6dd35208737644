#!/bin/sh
# Enter a throwaway Debian root (tests/seats/debian.py): run inside `unshare --mount --pid --fork`, as root.
# usage: enter-root.sh LOWER TOP "BIND_DIRS" "CACHES" SCRIPT
#   LOWER  the pristine root (read-only lower layer)     TOP  holds upper/, work/ and merged/
#   BIND_DIRS  host folders bound read-only at the same place (the local package folders pip's configuration names)
#   CACHES     HOST=INSIDE pairs bound read-write: download caches kept between runs (apt's .debs, pip's wheels)
#   SCRIPT     run by bash inside, as root, with a clean environment
set -eu
LOWER=$1 TOP=$2 BINDS=$3 CACHES=$4 SCRIPT=$5
ROOT="$TOP/merged"
mount -t overlay overlay -o "lowerdir=$LOWER,upperdir=$TOP/upper,workdir=$TOP/work" "$ROOT"
mount -t proc proc "$ROOT/proc"
mount --rbind /dev "$ROOT/dev"
mount -t sysfs sysfs "$ROOT/sys" 2>/dev/null || true
mount -t tmpfs tmpfs "$ROOT/tmp"
for dir in $BINDS; do
  mkdir -p "$ROOT$dir"
  mount --bind "$dir" "$ROOT$dir"
  mount -o remount,bind,ro "$ROOT$dir"
done
for pair in $CACHES; do
  mkdir -p "$ROOT${pair#*=}"
  mount --bind "${pair%%=*}" "$ROOT${pair#*=}"
done
cp /etc/resolv.conf "$ROOT/etc/resolv.conf" 2>/dev/null || true
cd "$ROOT"
mkdir -p .old-root
pivot_root . .old-root
cd /
umount -l /.old-root
rmdir /.old-root
exec env -i HOME=/root LANG=C.UTF-8 TERM=dumb PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  bash -c "$SCRIPT"
