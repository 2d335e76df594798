#!/usr/bin/env bash
# Cheap checks of the user guide (ctest docs.links; needs no build):
#   - README.md has at most 300 lines;
#   - the two commands of "Two commands (fresh Debian 12)" (`bash cmake/run.sh demo`, `bash cmake/run.sh test`,
#     written as lines of their own, as .ci/run and the README give them) are within its first 80 lines;
#   - every relative markdown link or image in README.md and docs/*.md resolves: the file exists and a `#anchor`
#     matches a heading of the target (GitHub's slugs: lower case, punctuation dropped, spaces to hyphens, -1, -2 ...
#     for repeated headings). Links inside fenced code blocks and inline code are not links.
# Usage: bash test/docs/check-docs.sh [repository root]   (default: the folder two levels above this script)
set -uo pipefail
export LC_ALL=C.UTF-8

root="${1:-$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)}"
cd "$root" || { echo "check-docs: cannot enter '$root'" >&2; exit 2; }

max_lines=300
command_within=80
failures=0
fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

readme=README.md
[ -f "$readme" ] || { echo "FAIL: $root/$readme not found" >&2; exit 1; }

lines=$(wc -l <"$readme")
if [ "$lines" -gt "$max_lines" ]; then
  fail "$readme has $lines lines; at most $max_lines (move details to docs/)"
fi

for cmd in 'bash cmake/run.sh demo' 'bash cmake/run.sh test'; do
  n=$(grep -n -m1 -E "^${cmd//./\\.}([[:space:]]|\$)" "$readme" | cut -d: -f1)
  if [ -z "$n" ]; then
    fail "$readme: no line starting with '$cmd' (the two commands of \"Two commands (fresh Debian 12)\")"
  elif [ "$n" -gt "$command_within" ]; then
    fail "$readme:$n: '$cmd' is on line $n; it must be within the first $command_within lines"
  fi
done

# The file's lines with fenced code blocks blanked (line numbers kept) and inline code removed.
prose() {
  awk '/^[[:space:]]*(```|~~~)/ { fence = !fence; print ""; next } { print fence ? "" : $0 }' "$1" | sed -E 's/`[^`]*`//g'
}

# GitHub's heading anchors of a markdown file, one a line.
slugs() {
  awk '/^[[:space:]]*(```|~~~)/ { fence = !fence; next } !fence && /^#+[ \t]/' "$1" |
    sed -E 's/^#{1,6}[[:space:]]+//; s/[[:space:]]+#+[[:space:]]*$//; s/!?\[([^]]*)\]\([^)]*\)/\1/g; s/<[^>]*>//g' |
    tr '[:upper:]' '[:lower:]' |
    sed -E 's/[^[:alnum:] _-]//g; s/ /-/g' |
    awk '{ s = $0; if (s in seen) { seen[s]++; s = s "-" seen[s] } else seen[s] = 0; print s }'
}

checked=0
files=("$readme")
for f in docs/*.md; do
  [ -f "$f" ] && files+=("$f")
done
for file in "${files[@]}"; do
  dir=$(dirname "$file")
  while IFS=: read -r lineno link; do
    target=${link#*](}
    target=${target%)}
    target=${target%% *} # drop an optional "title"
    target=${target#<}
    target=${target%>}
    case "$target" in
      '' | [a-zA-Z]*:* | //*) continue ;; # empty, or absolute (http:, https:, mailto:, ...)
    esac
    checked=$((checked + 1))
    path=${target%%#*}
    anchor=""
    [ "$path" != "$target" ] && anchor=${target#*#}
    if [ -z "$path" ]; then
      resolved=$file
    else
      resolved="$dir/$path"
      if [ ! -e "$resolved" ]; then
        fail "$file:$lineno: link '$target': $resolved does not exist"
        continue
      fi
    fi
    if [ -n "$anchor" ]; then
      case "$resolved" in
        *.md)
          if ! slugs "$resolved" | grep -qxF -- "$anchor"; then
            fail "$file:$lineno: link '$target': no heading of $resolved has the anchor '#$anchor'"
          fi
          ;;
        *) fail "$file:$lineno: link '$target': an anchor into a file that is not markdown" ;;
      esac
    fi
  done < <(prose "$file" | grep -noE '\]\([^)[:space:]]*([[:space:]]+"[^"]*")?\)')
done

if [ "$failures" -gt 0 ]; then
  echo "check-docs: $failures problem(s) in $root (README.md and docs/*.md; $checked relative links checked)" >&2
  exit 1
fi
echo "check-docs: OK: $readme $lines lines (at most $max_lines), the two commands within its first $command_within," \
  "$checked relative links in ${#files[@]} files resolve"
