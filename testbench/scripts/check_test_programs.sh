#!/usr/bin/env bash
# Every program outside the project that the test suite runs comes from a
# package scripts/setup.sh installs (with the options scripts/test.sh gives it)
# or from one every Debian system has (Priority: required, as a debootstrap
# minbase holds). A fresh machine then runs the whole suite after set-up.
#
# The programs are found in what the suite runs: the command words of its
# shell scripts, absolute program paths (/usr/bin/time) anywhere in
# testbench/ and the scripts the tests call, CMake COMMAND words, programs
# named in Python subprocess calls, and the shell std::system() uses.
#   check_test_programs.sh SOURCE_DIR
set -uo pipefail
src=$1
setup=$src/scripts/setup.sh
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

# With the options scripts/test.sh gives it (the whole suite).
options=$(grep -oE '^[^#]*scripts/setup\.sh( +--[a-z]+)*' "$src/scripts/test.sh" | head -n1 | grep -oE -- '--[a-z]+' | tr '\n' ' ')
[ -n "$options" ] || { echo "FAIL: scripts/test.sh does not run scripts/setup.sh with its options"; exit 1; }
mapfile -t listed < <(bash "$setup" --list $options)
((${#listed[@]} > 5)) || { echo "FAIL: setup.sh --list printed no package list"; exit 1; }
# What installing them brings: the listed packages and, recursively, what they
# depend on (as installed here; slurm-wlm brings slurmd, python3 its interpreter).
declare -A brought
while read -r p; do brought[$p]=1; done < <(
  dpkg-query -W -f='${Package}\t${Depends}, ${Pre-Depends}, ${Provides}\n' 2>/dev/null |
  awk -F'\t' -v want="$(printf '%s ' "${listed[@]}")" '
    { deps[$1] = $2 }
    END {
      n = split(want, q, " "); for (i = 1; i <= n; i++) seen[q[i]] = 1
      while (n > 0) {
        p = q[n--]; print p
        m = split(deps[p], d, /[,|]/)
        for (j = 1; j <= m; j++) {
          x = d[j]; sub(/^[ \t]+/, "", x); sub(/[ \t:(].*/, "", x)
          if (x != "" && !(x in seen) && (x in deps)) { seen[x] = 1; q[++n] = x }
        }
      }
    }')

# Command words of a shell script: the first word of each simple command
# (line start, after | || && ; $( ( { and the keywords that open a body).
# Comments and here-document bodies are skipped.
shell_commands() {
  awk '
    heredoc != "" { if ($0 ~ "^[ \t]*" heredoc "[ \t]*$") heredoc = ""; next }
    {
      line = $0
      gsub(/\$?\(\([^)]*\)\)/, " ", line)   # arithmetic
      if (!sq && !dq && match(line, /<<-?[ \t]*["'"'"'\\]?[A-Za-z_]+/)) {
        tag = substr(line, RSTART, RLENGTH); gsub(/[<"'"'"'\\ \t-]/, "", tag); pending = tag
      }
      # Quoted text (across lines, as awk and Python programs are) becomes Q;
      # separators outside quotes become line breaks; comments go.
      out = ""; prev = " "
      for (i = 1; i <= length(line); i++) {
        ch = substr(line, i, 1)
        if (sq) { if (ch == "'"'"'") sq = 0; out = out "%"; continue }
        if (dq) { if (ch == "\\") { i++; out = out "%"; continue } if (ch == "\"") dq = 0; out = out "%"; continue }
        if (ch == "'"'"'") { sq = 1; out = out "%"; prev = ch; continue }
        if (ch == "\"") { dq = 1; out = out "%"; prev = ch; continue }
        if (ch == "#" && prev ~ /[ \t;(|&]/) break
        if (ch ~ /[|;&(){}`]/) ch = "\n"
        if (ch == "$" && substr(line, i + 1, 1) == "(") ch = " "
        out = out ch; prev = ch
      }
      if (pending != "") { heredoc = pending; pending = "" }
      if (match(line, /^[ \t]*[^ \t()|]+(\|[^ \t()|]+)*\)/))   # a case pattern
        out = substr(out, RLENGTH + 1)
      n = split(out, parts, "\n")
      for (j = 1; j <= n; j++) {
        seg = parts[j]
        m = split(seg, w, /[ \t]+/); k = 1
        while (k <= m && (w[k] == "" || w[k] ~ /^(then|do|else|elif|if|while|until|!|time|exec|command|env|in)$/ || w[k] ~ /^[A-Za-z_][A-Za-z0-9_]*=/ || w[k] ~ /^-/)) k++
        if (k <= m && w[k - 1] != "in") print w[k]
      }
    }' "$1" | grep -E '^[A-Za-z/][A-Za-z0-9_./+-]*$' || true
}
functions_of() { grep -oE '^[ \t]*[A-Za-z_][A-Za-z0-9_]*\(\)' "$1" | tr -d ' \t()' || true; }

declare -A found   # program -> where
add() { [ -n "${found[$1]:-}" ] || found[$1]=$2; }

# testbench/ shell scripts and the scripts the suite itself calls.
for f in $(find "$src/testbench" -name '*.sh') "$src/scripts/test.sh"; do
  fns=" $(functions_of "$f" | tr '\n' ' ') "
  while read -r w; do
    case "$w" in STR|*/rbcd-*|rbcd-*|./*) continue ;; esac
    [[ $fns == *" $w "* ]] && continue
    t=$(type -t "$w" 2>/dev/null || true)
    [ "$t" = builtin ] || [ "$t" = keyword ] && continue
    add "$w" "${f#$src/}"
  done < <(shell_commands "$f")
done
# Absolute program paths anywhere the suite reads from.
while IFS=: read -r f p; do
  add "$p" "${f#$src/}"
done < <(grep -roE '(^|[^A-Za-z0-9_./-])/(usr/)?s?bin/[a-z][a-z0-9_+-]*' "$src/testbench" "$src/vectors" \
           "$src/python/rbcd" "$src/scripts/reproduce.sh" |
         grep -v '^[^:]*/check_test_programs.sh:' | sed -E 's#:[^/]*(/(usr/)?s?bin/)#:\1#')
# CMake COMMAND words that name a program, not a variable or target.
while IFS=: read -r f w; do
  add "$w" "${f#$src/}"
done < <(grep -roE 'COMMAND +[A-Za-z][A-Za-z0-9_.+-]*( |$)' --include=CMakeLists.txt --include='*.cmake' \
           "$src/testbench" "$src/vectors" "$src/fuzz" | sed -E 's/COMMAND +//; s/ $//')
# Programs named first in a Python subprocess call (in *.py, the package in
# python/, and the scripts/ launchers written in Python).
python_files=()
while IFS= read -r f; do
  case "$f" in *.py) python_files+=("$f") ;; *) head -n1 "$f" | grep -q python && python_files+=("$f") ;; esac
done < <(find "$src/testbench" "$src/scripts" "$src/python" -type f -not -path '*/__pycache__/*')
while IFS=: read -r f w; do
  add "$w" "${f#$src/}"
done < <(grep -oE '(run|Popen|check_output|check_call|call)\(\[ *"[a-z][a-z0-9_.+-]*"' "${python_files[@]}" |
         sed -E 's/:.*"([^"]*)"$/:\1/')
# std::system() runs /bin/sh.
grep -rqE 'std::system\(' "$src/testbench" && add /bin/sh "std::system() in testbench/"

# Where each program lives, and which package owns that file: one dpkg-query
# for all of them (usrmerge: /bin/sh is packaged as /bin/sh, found as /usr/bin/sh).
declare -A path_of
queries=()
for prog in "${!found[@]}"; do
  path=$prog
  # Where a Debian system has it, not where this shell's PATH (pyenv, /usr/local) finds it.
  [[ $prog == /* ]] || path=$(PATH=/usr/sbin:/usr/bin:/sbin:/bin command -v "$prog" 2>/dev/null || true)
  if [ -z "$path" ] || [ ! -e "$path" ]; then
    fail "${found[$prog]} runs $prog, which is not installed here: add its package to scripts/setup.sh"
    continue
  fi
  real=$(readlink -f "$path")
  path_of[$prog]="$real $path ${real#/usr} ${path#/usr}"
  queries+=($real $path ${real#/usr} ${path#/usr})
done
declare -A owner
while IFS= read -r line; do
  case "$line" in diversion*) continue ;; esac
  f=${line##*: }
  [ -n "${owner[$f]:-}" ] || owner[$f]=${line%%: *}
done < <(dpkg-query -S "${queries[@]}" 2>/dev/null)

checked=0
for prog in "${!path_of[@]}"; do
  where=${found[$prog]}
  pkg=""
  for f in ${path_of[$prog]}; do
    [ -n "$pkg" ] || pkg=${owner[$f]:-}
  done
  if [ -z "$pkg" ]; then
    fail "$where runs $prog (${path_of[$prog]%% *}), which no Debian package provides"
    continue
  fi
  pkg=${pkg%%,*}
  pkg=${pkg%%:*}
  checked=$((checked + 1))
  prio=$(dpkg-query -W -f='${Priority}' "$pkg" 2>/dev/null || true)
  [ "$prio" = required ] && continue
  [ -n "${brought[$pkg]:-}" ] ||
    fail "$where runs $prog from package $pkg (priority $prio), which scripts/setup.sh does not install"
done
((checked > 10)) || fail "only $checked programs found: the scan missed the suite's scripts"

if [ "$fails" -ne 0 ]; then echo "$fails program(s) not installed by scripts/setup.sh"; exit 1; fi
echo "check_test_programs.sh: the $checked external programs the suite runs all come from setup.sh's packages or the required ones"
