#!/usr/bin/env bash
# scripts/setup.sh on a system it cannot change: runs it with PATH holding only
# shims (dpkg-query reporting chosen packages missing, id, sudo, apt-get that
# log their calls), so no package is ever installed. Checks the exit status,
# the message and which commands ran, for root, sudo and neither.
#   test_setup.sh PATH/TO/setup.sh
set -u
setup=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# make_shims DIR UID MISSING SUDO(yes|no|broken) DPKG(yes|no)
make_shims() {
  local d=$1 uid=$2 miss=$3 sudo=$4 dpkg=$5
  rm -rf "$d"; mkdir -p "$d"
  for tool in grep env; do ln -s "$(command -v $tool)" "$d/$tool"; done
  printf '#!/bin/bash\necho %s\n' "$uid" >"$d/id"
  if [ "$dpkg" = yes ]; then
    cat >"$d/dpkg-query" <<SHIM
#!/bin/bash
for m in $miss; do [ "\${!#}" = "\$m" ] && { echo "dpkg-query: no packages found matching \$m" >&2; exit 1; }; done
printf 'install ok installed'
SHIM
  fi
  printf '#!/bin/bash\necho "apt-get $*" >>"%s/calls"\n' "$work" >"$d/apt-get"
  case $sudo in
    yes) printf '#!/bin/bash\necho "sudo $*" >>"%s/calls"\nexec "$@"\n' "$work" >"$d/sudo" ;;
    broken) printf '#!/bin/bash\necho "sudo: a password is required" >&2\nexit 1\n' >"$d/sudo" ;;
  esac
  chmod +x "$d"/*
  rm -f "$work/calls"
}

# run_setup: runs setup.sh with only the shims on PATH; sets rc, out, err, calls.
run_setup() {
  PATH="$work/bin" /bin/bash "$setup" >"$work/out" 2>"$work/err"
  rc=$?
  out=$(<"$work/out"); err=$(<"$work/err")
  calls=$(cat "$work/calls" 2>/dev/null || true)
}

# 1. Not root, no sudo, two packages missing: exit 1, both named, the command
#    to run as root given, nothing attempted, no shell error.
make_shims "$work/bin" 1000 "libsystemc-dev catch2" no yes
run_setup
[ "$rc" = 1 ] || fail "no root, no sudo: exit status $rc, expected 1"
for p in libsystemc-dev catch2; do
  grep -q "missing Debian packages:.*$p" <<<"$err" || fail "no root, no sudo: $p not listed in: $err"
done
grep -q "apt-get install --no-install-recommends libsystemc-dev catch2" <<<"$err" ||
  fail "no root, no sudo: no install command in: $err"
grep -q "not root and no sudo" <<<"$err" || fail "no root, no sudo: reason not given in: $err"
grep -q "libcli11-dev" <<<"$err" && fail "no root, no sudo: an installed package listed: $err"
grep -qi "command not found\|line [0-9]" <<<"$err" && fail "no root, no sudo: shell error: $err"
[ -z "$calls" ] || fail "no root, no sudo: ran: $calls"
[ -z "$out" ] || fail "no root, no sudo: stdout not empty: $out"

# 2. Nothing missing: exit 0, silent, nothing run, even without root or sudo.
make_shims "$work/bin" 1000 "" no yes
run_setup
[ "$rc" = 0 ] || fail "all installed: exit status $rc: $err"
[ -z "$err$out" ] || fail "all installed: output: $out$err"
[ -z "$calls" ] || fail "all installed: ran: $calls"

# 3. Root: apt-get installs exactly the missing packages, exit 0.
make_shims "$work/bin" 0 "ninja-build" no yes
run_setup
[ "$rc" = 0 ] || fail "root: exit status $rc: $err"
grep -q "^apt-get install .*--no-install-recommends ninja-build$" <<<"$calls" || fail "root: calls were: $calls"

# 4. Not root with sudo: the same through sudo.
make_shims "$work/bin" 1000 "libpng-dev" yes yes
run_setup
[ "$rc" = 0 ] || fail "sudo: exit status $rc: $err"
grep -q "^sudo env DEBIAN_FRONTEND=noninteractive apt-get install .* libpng-dev$" <<<"$calls" || fail "sudo: calls were: $calls"

# 5. sudo refuses: exit 1 with the list, not sudo's message alone.
make_shims "$work/bin" 1000 "libpng-dev" broken yes
run_setup
[ "$rc" = 1 ] || fail "sudo refuses: exit status $rc"
grep -q "missing Debian packages: libpng-dev" <<<"$err" || fail "sudo refuses: no list in: $err"

# 6. No dpkg-query (not Debian): exit 1, every package listed.
make_shims "$work/bin" 1000 "" no no
run_setup
[ "$rc" = 1 ] || fail "no dpkg-query: exit status $rc"
grep -q "dpkg-query not found" <<<"$err" || fail "no dpkg-query: reason not given in: $err"
grep -q "missing Debian packages: g++ cmake .* libpng-dev" <<<"$err" || fail "no dpkg-query: list not complete: $err"

# 7. --list: the packages one a line, nothing run, even with every package missing.
make_shims "$work/bin" 1000 "time libsystemc-dev" no yes
PATH="$work/bin" /bin/bash "$setup" --list --slurm >"$work/out" 2>"$work/err"
rc=$?
[ "$rc" = 0 ] || fail "--list: exit status $rc: $(<"$work/err")"
for p in libsystemc-dev time slurm-wlm; do grep -qx "$p" "$work/out" || fail "--list: $p not listed"; done
[ ! -s "$work/calls" ] || fail "--list: ran: $(<"$work/calls")"

if [ "$fails" -ne 0 ]; then echo "$fails check(s) failed"; exit 1; fi
echo "setup.sh: 7 scenarios passed"
