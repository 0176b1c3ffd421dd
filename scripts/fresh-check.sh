#!/usr/bin/env bash
# Runs COMMAND as a new user would: in a brand-new Debian 12 root, in a clean clone of this repository's
# committed HEAD, with ../shared beside it (read-only). Exits with COMMAND's status.
#
#   bash scripts/fresh-check.sh 'bash scripts/test.sh'
#   bash scripts/fresh-check.sh 'bash scripts/demo.sh && ls demo-out'
#
# The root is `mmdebstrap --variant=apt bookworm` on the host's apt sources, plus git (the user cloned the
# repository with it); nothing else. It is a tarball cached in $TPKIT_FRESH_CACHE (default
# /var/cache/tpkit-fresh), made again when older than $TPKIT_FRESH_MAX_AGE_DAYS (default 7) or when the
# host's sources change. Downloaded .deb files are kept in the cache's archives/ folder between runs
# (TPKIT_FRESH_APT_CACHE=0 turns that off): a download cache only, every package is still installed by
# the project's own scripts in every run; so is a compiler cache, $cache/ccache (TPKIT_FRESH_CCACHE=0
# turns it off; see below). Variables named TPKIT_* and CI are passed into the root.
# Run as root; installs mmdebstrap on the host when it is missing. Uncommitted changes are not seen.
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 'COMMAND'" >&2; exit 2; }
command_line=$1
[ "$(id -u)" = 0 ] || { echo "fresh-check: run as root (it makes a chroot)" >&2; exit 2; }

repo=$(git -C "$(dirname "$0")" rev-parse --show-toplevel)
head=$(git -C "$repo" rev-parse HEAD)
shared=$(cd "$repo/.." && pwd)/shared
[ -d "$shared" ] || { echo "fresh-check: $shared: missing (the repository expects ../shared beside it)" >&2; exit 2; }
cache=${TPKIT_FRESH_CACHE:-/var/cache/tpkit-fresh}
max_age_days=${TPKIT_FRESH_MAX_AGE_DAYS:-7}
mkdir -p "$cache"

t_start=$(date +%s)
elapsed() { echo $(( $(date +%s) - $1 )); }
say() { echo "fresh-check: $*" >&2; }

if ! command -v mmdebstrap >/dev/null; then
  say "installing mmdebstrap on the host"
  DEBIAN_FRONTEND=noninteractive apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends mmdebstrap >/dev/null
fi

root=""
sources=""
cleanup() {
  local status=$?
  [ -z "$sources" ] || rm -f "$sources"
  if [ -n "$root" ] && [ -d "$root" ]; then
    # processes still running inside the root (a daemon a test left) hold its mounts
    local pid
    for pid in $(ls /proc | grep -E '^[0-9]+$'); do
      [ "$(readlink "/proc/$pid/root" 2>/dev/null)" = "$root" ] && kill -9 "$pid" 2>/dev/null || true
    done
    sleep 0.2
    umount -R "$root/work/shared" 2>/dev/null || umount -lR "$root/work/shared" 2>/dev/null || true
    umount -R "$root/var/cache/apt/archives" 2>/dev/null || umount -lR "$root/var/cache/apt/archives" 2>/dev/null || true
    umount -R "$root/var/cache/ccache" 2>/dev/null || umount -lR "$root/var/cache/ccache" 2>/dev/null || true
    umount -R "$root/dev" 2>/dev/null || umount -lR "$root/dev" 2>/dev/null || true
    umount -R "$root/sys" 2>/dev/null || umount -lR "$root/sys" 2>/dev/null || true
    umount -R "$root/proc" 2>/dev/null || umount -lR "$root/proc" 2>/dev/null || true
    if findmnt -rn -o TARGET | grep -q "^$root"; then
      say "left $root in place: still mounted: $(findmnt -rn -o TARGET | grep "^$root" | tr '\n' ' ')"
    else
      rm -rf --one-file-system "$root"
    fi
  fi
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# The host's apt sources, deb822 or one-line form, as one file mmdebstrap reads.
if ls /etc/apt/sources.list.d/*.sources >/dev/null 2>&1; then
  sources=$(mktemp --suffix=.sources /tmp/tpkit-fresh.XXXXXX)
  cat /etc/apt/sources.list.d/*.sources > "$sources"
else
  sources=$(mktemp --suffix=.list /tmp/tpkit-fresh.XXXXXX)
  cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null | grep -E '^\s*deb ' > "$sources"
fi
key=$( { cat "$sources"; echo "variant=apt include=git"; } | sha256sum | cut -c1-12)
tarball=$cache/bookworm-apt-$key.tar

t0=$(date +%s)
if [ -f "$tarball" ] && [ -z "$(find "$tarball" -mtime +"$max_age_days")" ]; then
  say "root: cached $tarball"
else
  say "root: mmdebstrap --variant=apt bookworm (host sources) -> $tarball"
  rm -rf "$cache"/bookworm-apt-*.tar "$cache"/bookworm-apt-*.tar.tmp
  mmdebstrap --quiet --format=tar --variant=apt --include=git bookworm "$tarball.tmp" "$sources" </dev/null
  mv "$tarball.tmp" "$tarball"
fi
t_mmdebstrap=$(elapsed "$t0")

root=$(mktemp -d /var/tmp/tpkit-fresh.XXXXXX)
tar -C "$root" -xpf "$tarball"
cp /etc/resolv.conf "$root/etc/resolv.conf" 2>/dev/null || true
# apt options of the host that its sources need (e.g. a snapshot mirror's expired Release files)
for f in /etc/apt/apt.conf.d/*; do
  grep -qE 'Check-Valid-Until|Check-Date|Acquire::(http|https)::Proxy' "$f" 2>/dev/null && cp "$f" "$root/etc/apt/apt.conf.d/"
done

# /etc/hosts as Debian's installer writes it (mmdebstrap writes none, and without it "localhost" does
# not resolve: the single-node Slurm of the tests needs it)
printf '127.0.0.1\tlocalhost\n127.0.1.1\t%s\n::1\tlocalhost ip6-localhost ip6-loopback\n' "$(hostname)" > "$root/etc/hosts"

# /proc, and a /dev of its own with the usual nodes (not the host's /dev, which a stray rm would reach)
mount -t proc proc "$root/proc"
mount -t tmpfs -o mode=755,nosuid tmpfs "$root/dev"
for n in null zero full random urandom tty; do
  touch "$root/dev/$n"
  mount --bind "/dev/$n" "$root/dev/$n"
done
mkdir -p "$root/dev/pts" "$root/dev/shm"
mount -t devpts -o newinstance,ptmxmode=0666,mode=620 devpts "$root/dev/pts" 2>/dev/null ||
  mount --bind /dev/pts "$root/dev/pts"
ln -s pts/ptmx "$root/dev/ptmx"
mount -t tmpfs -o mode=1777,nosuid,nodev tmpfs "$root/dev/shm"
ln -s /proc/self/fd "$root/dev/fd"
ln -s /proc/self/fd/0 "$root/dev/stdin"
ln -s /proc/self/fd/1 "$root/dev/stdout"
ln -s /proc/self/fd/2 "$root/dev/stderr"

# /sys as a machine has it, read-only: a sysfs of its own and the host's cgroup hierarchies bound one by
# one, each read-only (slurmd, which the tests start, needs the cgroup filesystem to initialize)
mount -t sysfs -o ro,nosuid,nodev,noexec sysfs "$root/sys"
while read -r m; do
  [ -d "$root$m" ] || continue
  mount --bind "$m" "$root$m" && mount -o remount,bind,ro "$root$m"
done < <(findmnt -rn -o TARGET | grep -E '^/sys/fs/cgroup(/|$)' | sort)

if [ "${TPKIT_FRESH_APT_CACHE:-1}" != 0 ]; then
  mkdir -p "$cache/archives/partial"
  mount --bind "$cache/archives" "$root/var/cache/apt/archives"
fi

# a compiler cache shared by the roots, in $cache/ccache (TPKIT_FRESH_CCACHE=0 turns it off): the
# build scripts compile through ccache when it is installed (scripts/compiler-cache.sh), so the demo
# root's build takes the objects the test root's identical compile commands made, and a later run those
# of the sources that did not change. A hit is the object the same compiler made from the same
# preprocessed source and flags: it changes no result, and every root still installs and builds.
ccache_env=()
if [ "${TPKIT_FRESH_CCACHE:-1}" != 0 ]; then
  mkdir -p "$cache/ccache" "$root/var/cache/ccache"
  [ -f "$cache/ccache/ccache.conf" ] || printf 'max_size = 8G\n' > "$cache/ccache/ccache.conf"
  mount --bind "$cache/ccache" "$root/var/cache/ccache"
  ccache_env=(CCACHE_DIR=/var/cache/ccache)
fi

mkdir -p "$root/work/shared"
mount --bind "$shared" "$root/work/shared"
mount -o remount,bind,ro "$root/work/shared"
git clone --quiet --no-local "$repo" "$root/work/tpkit"
git -C "$root/work/tpkit" checkout --quiet --detach "$head"
say "clone: $(git -C "$root/work/tpkit" log -1 --format='%h %s' | cut -c1-90)"

envs=(HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin LANG=C.UTF-8 TERM=dumb "${ccache_env[@]}")
while IFS='=' read -r name _; do
  case $name in TPKIT_FRESH_*) ;; TPKIT_*|CI) envs+=("$name=${!name}") ;; esac
done < <(env)

say "run: $command_line"
t0=$(date +%s)
set +e
chroot "$root" /usr/bin/env -i "${envs[@]}" /bin/bash -c "cd /work/tpkit && $command_line" </dev/null
status=$?
set -e
t_command=$(elapsed "$t0")
say "times: root ${t_mmdebstrap} s, command ${t_command} s, total $(elapsed "$t_start") s; exit status $status"
exit "$status"
