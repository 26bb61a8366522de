#!/usr/bin/env bash
# The plot tools, called from a Python without matplotlib and numpy, say what is missing and how to
# get it instead of a traceback (issue #28 item 7; tools/python_deps.py). `python3 -S` skips the
# site packages, so Debian's own Python stands for one without them; TURBID_PY_REEXEC=1 stops the
# tool re-running itself with /usr/bin/python3. Reference: the message's promised wording.
set -uo pipefail
root="$1"
py="$(command -v python3 || true)"
[[ -n "$py" ]] || { echo "no python3: nothing to check"; exit 0; }
fail=0
for tool in plot_forces plot_snapshot plot_landslide; do
  out="$(TURBID_PY_REEXEC=1 "$py" -S "$root/tools/$tool" /nonexistent 2>&1)"
  rc=$?
  if ((rc == 0)); then
    echo "FAIL $tool: exit 0 without its modules"; fail=1; continue
  fi
  if ! grep -q "has no .*matplotlib" <<<"$out" || ! grep -q "apt-get install .*python3-matplotlib" <<<"$out"; then
    echo "FAIL $tool: the message does not name what is missing and how to get it:"; echo "$out"; fail=1; continue
  fi
  if grep -q "Traceback" <<<"$out"; then
    echo "FAIL $tool: a traceback"; echo "$out"; fail=1; continue
  fi
  echo "ok   $tool: $(head -c 160 <<<"$out")"
done
exit "$fail"
