#!/usr/bin/env bash
# Runs the README's two commands on a bare Debian 12, as a new user would, and says whether they
# pass. Catches a package missing from scripts/install_deps.sh that a development machine hides.
#
#   sudo scripts/check_fresh_machine.sh [--keep-root]
#
# What it does:
#  1. debootstrap --variant=minbase bookworm into a temporary folder, from this machine's Debian
#     mirror; copies in this machine's apt sources, apt settings and resolv.conf; mounts proc;
#  2. puts the project there as `git archive HEAD` (committed work only: no build folder, no git,
#     no ../shared; uncommitted changes are not checked, and a warning says so);
#  3. runs each command of the README's first code block exactly as written, as root, under
#     `env -i` (an empty environment), one after the other in the same root;
#  4. prints pass or fail and the time of each, and the folder of the logs (kept);
#  5. unmounts and deletes the root (unless --keep-root).
#
# Needs root, debootstrap (installed when missing) and the network to the Debian mirror. It takes
# about 10-15 minutes, so it is not part of the test suite: run it before resolving any change to
# the dependencies, CMake or the scripts. Exit code 0 when every command passed.
set -euo pipefail

keep_root=0
for arg in "$@"; do
  case "$arg" in
    --keep-root) keep_root=1 ;;
    -h | --help) sed -n '2,19p' "$0"; exit 0 ;;
    *) echo "check_fresh_machine: unknown argument '$arg'" >&2; exit 2 ;;
  esac
done

if [[ "$(id -u)" -ne 0 ]]; then
  echo "check_fresh_machine: needs root (debootstrap, chroot, mount)" >&2
  exit 2
fi
repo="$(git -C "$(dirname "$0")" rev-parse --show-toplevel)"
cd "$repo"

# The README's commands: the indented `./scripts/...` lines of its first block, comments removed.
mapfile -t commands < <(awk 'NR <= 12 && /^    \.\/scripts\// { sub(/[[:space:]]+#.*$/, ""); sub(/^    /, ""); print }' README.md)
if [[ ${#commands[@]} -eq 0 ]]; then
  echo "check_fresh_machine: found no './scripts/...' command in the README's first lines" >&2
  exit 2
fi
if ! git diff --quiet HEAD -- || [[ -n "$(git ls-files --others --exclude-standard)" ]]; then
  echo "check_fresh_machine: warning: the work tree has uncommitted changes; checking HEAD only"
fi

if ! command -v debootstrap >/dev/null 2>&1; then
  echo "check_fresh_machine: installing debootstrap"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap >/dev/null
fi

# This machine's Debian mirror (deb822 sources first, then the one-line format).
mirror="$(awk '/^URIs:/ && $2 ~ /\/debian\/?$/ { print $2; exit }' /etc/apt/sources.list.d/*.sources 2>/dev/null || true)"
if [[ -z "$mirror" ]]; then
  mirror="$(awk '$1 == "deb" && $2 ~ /\/debian\/?$/ { print $2; exit }' /etc/apt/sources.list 2>/dev/null || true)"
fi
mirror="${mirror:-http://deb.debian.org/debian}"

work="$(mktemp -d /var/tmp/timeopt-fresh.XXXXXX)"
logs="$(mktemp -d /tmp/timeopt-fresh-logs.XXXXXX)"
root="$work/root"

cleanup() {
  local mounted
  # Unmount everything below the root, deepest first.
  local real
  real="$(readlink -f "$root")"
  mounted="$(awk -v r="$real" '$2 == r || index($2, r "/") == 1 { print $2 }' /proc/mounts | sort -r)"
  for m in $mounted; do umount -l "$m" 2>/dev/null || true; done
  if [[ $keep_root -eq 0 ]]; then
    if awk -v r="$real" '$2 == r || index($2, r "/") == 1 { found = 1 } END { exit !found }' /proc/mounts; then
      echo "check_fresh_machine: something is still mounted under $root; not deleting $work" >&2
    else
      # Never into another file system, whatever was left behind.
      rm -rf --one-file-system "$work" || true
    fi
  else
    echo "check_fresh_machine: root kept at $root (proc unmounted)"
  fi
}
trap cleanup EXIT

elapsed() { local s=$1; printf '%dm%02ds' $((s / 60)) $((s % 60)); }

echo "check_fresh_machine: HEAD $(git rev-parse --short HEAD); root $root; logs $logs"
t0=$SECONDS
if ! debootstrap --variant=minbase bookworm "$root" "$mirror" >"$logs/debootstrap.log" 2>&1; then
  echo "check_fresh_machine: FAIL: debootstrap (see $logs/debootstrap.log)"
  exit 1
fi
echo "debootstrap minbase bookworm: $(elapsed $((SECONDS - t0)))"

rm -f "$root/etc/apt/sources.list"
cp -a /etc/apt/sources.list.d/. "$root/etc/apt/sources.list.d/" 2>/dev/null || true
[[ -f /etc/apt/sources.list ]] && cp /etc/apt/sources.list "$root/etc/apt/sources.list"
cp -a /etc/apt/apt.conf.d/. "$root/etc/apt/apt.conf.d/" 2>/dev/null || true
cp -L /etc/resolv.conf "$root/etc/resolv.conf"
mount -t proc proc "$root/proc"
mkdir -p "$root/project"
git archive HEAD | tar -x -C "$root/project"

status=0
summary=()
for i in "${!commands[@]}"; do
  cmd="${commands[$i]}"
  log="$logs/command_$((i + 1)).log"
  t=$SECONDS
  if chroot "$root" /usr/bin/env -i /bin/bash -c "cd /project && $cmd" >"$log" 2>&1; then
    result="PASS"
  else
    result="FAIL (exit $?)"
    status=1
  fi
  line="$result  $(elapsed $((SECONDS - t)))  $cmd  (log: $log)"
  summary+=("$line")
  echo "$line"
  tail -n 4 "$log" | sed 's/^/    | /'
done

echo
echo "check_fresh_machine: $([[ $status -eq 0 ]] && echo PASS || echo FAIL) on a bare Debian 12 (minbase bookworm), total $(elapsed $((SECONDS - t0)))"
printf '  %s\n' "${summary[@]}"
echo "  logs: $logs"
exit "$status"
