#!/usr/bin/env bash
# format.sh: format odotune's C++ sources (*.h, *.cpp) with clang-format and the
# repository's .clang-format.
#
#   bash scripts/format.sh           reformat every project file in place
#   bash scripts/format.sh --check   change nothing; list the files that are not
#                                    formatted and exit 1 if there are any
#
# Project files are the *.h / *.cpp files in the module folders (odotune/<module>/), in
# tests/ and bench/. build*/, cmake/ and everything
# else are skipped. The list comes from `git ls-files` (tracked files, and new files
# that are not ignored); outside a git checkout, find(1) is used instead.
# Works from any directory.
# Needs clang-format 14 (Debian/Ubuntu: apt-get install clang-format).
set -euo pipefail

script="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
cd "$(dirname "$script")/.."

usage() { sed -n '2,15p' "$script" | sed 's/^# \{0,1\}//'; }

check=0
case "${1:-}" in
  "") ;;
  --check) check=1 ;;
  -h | --help) usage; exit 0 ;;
  *) echo "format.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
esac
if [ $# -gt 1 ]; then echo "format.sh: too many arguments" >&2; usage >&2; exit 2; fi

CLANG_FORMAT="${CLANG_FORMAT:-clang-format}"
if ! command -v "$CLANG_FORMAT" >/dev/null 2>&1; then
  echo "format.sh: $CLANG_FORMAT not found; install it with: apt-get install clang-format" >&2
  exit 127
fi
if [ ! -f .clang-format ]; then
  echo "format.sh: no .clang-format in $(pwd)" >&2
  exit 2
fi
if ! "$CLANG_FORMAT" --style=file --dump-config >/dev/null; then
  echo "format.sh: $CLANG_FORMAT cannot read $(pwd)/.clang-format (see above)" >&2
  exit 2
fi

dirs=()
for d in odotune tests bench; do
  [ -d "$d" ] && dirs+=("$d")
done
if [ ${#dirs[@]} -eq 0 ]; then
  echo "format.sh: none of the project's source folders exist in $(pwd)" >&2
  exit 2
fi

files=()
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  # Tracked files, and new files not yet added (but not ignored ones such as build output).
  # `-- dir/*.h` matches at any depth in git pathspecs.
  while IFS= read -r -d '' f; do
    case "/$f" in */build*/*) continue ;; esac  # build output that is not ignored
    [ -f "$f" ] && files+=("$f")
  done < <(git ls-files -z --cached --others --exclude-standard -- \
             "${dirs[@]/%//*.h}" "${dirs[@]/%//*.cpp}" | sort -zu)
else
  while IFS= read -r -d '' f; do
    files+=("$f")
  done < <(find "${dirs[@]}" -type d -name 'build*' -prune -o \
             -type f \( -name '*.h' -o -name '*.cpp' \) -print0 | sort -z)
fi

if [ ${#files[@]} -eq 0 ]; then
  echo "format.sh: no C++ files found" >&2
  exit 0
fi

if [ "$check" -eq 1 ]; then
  bad=()
  for f in "${files[@]}"; do
    if ! "$CLANG_FORMAT" --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then
      bad+=("$f")
    fi
  done
  if [ ${#bad[@]} -gt 0 ]; then
    echo "format.sh: ${#bad[@]} of ${#files[@]} files are not formatted (run: bash scripts/format.sh):" >&2
    printf '  %s\n' "${bad[@]}" >&2
    exit 1
  fi
  echo "format.sh: all ${#files[@]} files are formatted"
else
  printf '%s\0' "${files[@]}" | xargs -0 -n 50 "$CLANG_FORMAT" --style=file -i
  echo "format.sh: formatted ${#files[@]} files"
fi
