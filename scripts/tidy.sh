#!/usr/bin/env bash
# tidy.sh: run clang-tidy with the repository's .clang-tidy over odotune's own
# translation units.
#
#   bash scripts/tidy.sh                    every project .cpp in build/compile_commands.json
#   bash scripts/tidy.sh BUILD_DIR          the same, with BUILD_DIR/compile_commands.json
#   bash scripts/tidy.sh [BUILD_DIR] FILE…  only these .cpp files (they must be in the database)
#
# Project translation units are the database entries under the module folders
# (odotune/<module>/), tests/ or bench/; any other entry (for example a
# dependency built with FetchContent) is skipped. Project headers are checked through the
# files that include them (HeaderFilterRegex in .clang-tidy).
# TIDY_DIRS (default "odotune tests bench") names the top folders whose units run,
# e.g. TIDY_DIRS=odotune for the library and CLI sources only (CI).
# clang-tidy runs under `nice -n 19`, as many at a time as nproc says (set TIDY_JOBS to
# change that). The exit status is non-zero if there is any finding (.clang-tidy has
# WarningsAsErrors: '*') or if a file cannot be parsed.
# The compile database comes from CMake (CMAKE_EXPORT_COMPILE_COMMANDS is ON in
# CMakeLists.txt): cmake -S . -B build. Needs clang-tidy 14 (apt-get install clang-tidy).
set -euo pipefail

script="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
root="$(cd "$(dirname "$script")/.." && pwd)"
usage() { sed -n '2,19p' "$script" | sed 's/^# \{0,1\}//'; }

case "${1:-}" in
  -h | --help) usage; exit 0 ;;
esac

# Arguments are taken relative to the directory the script was called from.
build_dir="$root/build"
if [ $# -gt 0 ] && [ -d "$1" ]; then
  build_dir="$(cd "$1" && pwd)"
  shift
fi
files=()
for f in "$@"; do
  if [ ! -f "$f" ]; then
    echo "tidy.sh: no such file: $f" >&2
    exit 2
  fi
  files+=("$(cd "$(dirname "$f")" && pwd)/$(basename "$f")")
done

tidy=""
for t in clang-tidy-14 clang-tidy; do
  if command -v "$t" >/dev/null 2>&1; then tidy="$(command -v "$t")"; break; fi
done
if [ -z "$tidy" ]; then
  echo "tidy.sh: clang-tidy not found; install it with: apt-get install clang-tidy" >&2
  exit 127
fi
runner=""
for r in run-clang-tidy-14 run-clang-tidy; do
  if command -v "$r" >/dev/null 2>&1; then runner="$(command -v "$r")"; break; fi
done
if ! command -v python3 >/dev/null 2>&1; then
  echo "tidy.sh: python3 not found (needed to read the compile database)" >&2
  exit 127
fi
db="$build_dir/compile_commands.json"
if [ ! -f "$db" ]; then
  echo "tidy.sh: no compile database at $db" >&2
  echo "  configure first (CMAKE_EXPORT_COMPILE_COMMANDS is on): cmake -S \"$root\" -B \"$build_dir\"" >&2
  exit 2
fi
if [ ! -f "$root/.clang-tidy" ]; then
  echo "tidy.sh: no .clang-tidy in $root" >&2
  exit 2
fi

# The project's translation units in the database, as run-clang-tidy names them
# (the entry's file made absolute against its directory), one per line;
# with FILE arguments, only those (each must be in the database).
# The test programs are unity builds (CMakeLists.txt): the database names
# each program's generated unity file, not its test files. clang-tidy gets a
# copy of the database in which every file a unity file includes has the
# unity file's command.
dbdir="$(mktemp -d)"
log="$(mktemp)"
trap 'rm -rf "$log" "$dbdir"' EXIT
units="$(TIDY_DIRS="${TIDY_DIRS:-odotune tests bench}" python3 - "$root" "$db" "$dbdir" "${files[@]}" <<'EOF'
import json, os, re, sys
root, db, dbdir, wanted = os.path.realpath(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4:]
modules = set(os.environ["TIDY_DIRS"].split())
entries = []
for e in json.load(open(db)):
    unity = e["file"] if os.path.isabs(e["file"]) else os.path.join(e["directory"], e["file"])
    if not re.search(r"/Unity/unity_[^/]*\.cxx$", unity):
        entries.append(e)
        continue
    for src in re.findall(r'^#include "([^"]+)"', open(unity).read(), re.M):
        entries.append(dict(e, file=src, command=e["command"].replace(e["file"], src)))
json.dump(entries, open(os.path.join(dbdir, "compile_commands.json"), "w"), indent=1)
units = {}
for e in entries:
    name = e["file"] if os.path.isabs(e["file"]) else os.path.normpath(os.path.join(e["directory"], e["file"]))
    rel = os.path.relpath(os.path.realpath(name), root)
    if rel.startswith("..") or rel.split(os.sep)[0] not in modules:
        continue
    units[os.path.realpath(name)] = name
if wanted:
    missing = [w for w in wanted if os.path.realpath(w) not in units]
    if missing:
        sys.exit("tidy.sh: not a project translation unit in " + db + ":\n  " + "\n  ".join(missing))
    names = [units[os.path.realpath(w)] for w in wanted]
else:
    names = sorted(units.values())
print("\n".join(names))
EOF
)"
if [ -z "$units" ]; then
  echo "tidy.sh: no project translation units in $db" >&2
  exit 2
fi
mapfile -t units <<<"$units"

jobs="${TIDY_JOBS:-$(nproc 2>/dev/null || echo 1)}"
echo "tidy.sh: clang-tidy on ${#units[@]} translation unit(s) from $db (-j$jobs, niced)" >&2

# clang's per-file "N warnings generated." counts the diagnostics that .clang-tidy hides.
noise='^[0-9]+ warnings? (and [0-9]+ errors? )?generated\.$'
set +e
if [ -n "$runner" ]; then
  # run-clang-tidy takes regexes; anchor and escape each path so exactly these files run.
  regexes=()
  for u in "${units[@]}"; do
    regexes+=("^$(printf '%s' "$u" | sed 's/[][\.*^$+?(){}|]/\\&/g')\$")
  done
  # clang-tidy finds .clang-tidy by walking up from each source file. The runner
  # echoes each clang-tidy command line (left out here) and turns colours on (removed).
  nice -n 19 "$runner" -clang-tidy-binary "$tidy" -p "$dbdir" -j "$jobs" -quiet "${regexes[@]}" 2>&1 |
    grep --line-buffered -v -F "$tidy --use-color " | sed -u 's/\x1b\[[0-9;]*m//g' |
    grep --line-buffered -v -E "$noise" | tee "$log"
  status=${PIPESTATUS[0]}
else
  # No run-clang-tidy: the same with xargs.
  printf '%s\0' "${units[@]}" |
    xargs -0 -n 1 -P "$jobs" nice -n 19 "$tidy" -p "$dbdir" --quiet 2>&1 |
    grep --line-buffered -v -E "$noise" | tee "$log"
  status=${PIPESTATUS[1]}
fi
set -e

findings=$(grep -cE '^[^ ].*:[0-9]+:[0-9]+: (warning|error):' "$log" || true)
if [ "$status" -ne 0 ] || [ "$findings" -ne 0 ]; then
  echo "tidy.sh: FAILED: $findings finding(s) in ${#units[@]} translation unit(s) (exit status $status)" >&2
  exit 1
fi
echo "tidy.sh: OK, no findings in ${#units[@]} translation unit(s)" >&2
