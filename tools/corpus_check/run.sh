#!/usr/bin/env bash
# Validate tests/data/mjcf against the system MuJoCo 2.2.2 (libmujoco-dev).
#   1. every corpus/*.xml loads with no error/warning and simulates cleanly (check.cc)
#   2. every broken/*.xml listed in broken/MANIFEST.tsv is rejected by MuJoCo exactly
#      when its mujoco_rejects column says "yes"
#   3. grammar coverage of the corpus against schema_2.2.2.txt is complete (coverage.py)
# Usage: tools/corpus_check/run.sh   (from anywhere; needs g++, libmujoco-dev, python3)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
g++ -O2 -std=c++17 "$root/tools/corpus_check/check.cc" -o "$tmp/check" -lmujoco

fail=0
echo "== corpus"
(cd "$root/tests/data/mjcf/corpus" && "$tmp/check" *.xml) || fail=1

echo "== broken"
cd "$root/tests/data/mjcf/broken"
while IFS=$'\t' read -r file efile eline esub rejects msg; do
  [[ "$file" == "file" ]] && continue
  out="$("$tmp/check" --steps 10 "$file" || true)"
  status="${out%%$'\t'*}"
  if [[ "$rejects" == "yes" && "$status" != "REJECT" ]] || [[ "$rejects" == "no" && "$status" == "REJECT" ]]; then
    echo "MISMATCH $file: manifest mujoco_rejects=$rejects, checker: $out"; fail=1
  else
    echo "ok       $file ($status)"
  fi
done < MANIFEST.tsv

echo "== coverage"
(cd "$root" && python3 tools/corpus_check/coverage.py) || fail=1
exit $fail
