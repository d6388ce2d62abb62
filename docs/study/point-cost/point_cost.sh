#!/usr/bin/env bash
# What one point costs at the corners of the thesis space (D 1–3 mm × gap 1–5 mm, μ = 0.3,
# v = 1.6 m/s): particles, steps, wall and CPU seconds of `sweep run`, one at a time.
# Prints a Markdown table (BENCHMARKS.md "One point"). Needs target/release/sweep (scripts/setup.sh).
set -euo pipefail
cd "$(dirname "$0")/../../.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/space.toml" <<'TOML'
name = "corners"
[parameters]
diameter = { lo = 1.0, hi = 3.0, unit = "mm" }
gap      = { lo = 1.0, hi = 5.0, unit = "mm" }
friction = 0.3
blade_speed = 1.6
TOML
echo "| D (mm) | gap (mm) | particles | settle steps | steps | dt (s) | wall (s) | CPU (s) | MFR | status |"
echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
for point in "1 1" "1 5" "3 1" "3 5"; do
  set -- $point
  /usr/bin/time -f "%e %U" -o "$tmp/time" target/release/sweep run "$tmp/space.toml" \
    --set "diameter=$1,gap=$2" --json > "$tmp/r.json" || true
  read -r wall cpu < "$tmp/time"
  python3 - "$tmp/r.json" "$1" "$2" "$wall" "$cpu" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
status = r.get("class", "done")
r = r.get("measured") or r  # an unsteady run keeps what it measured
if "steps" not in r:
    print(f"| {sys.argv[2]} | {sys.argv[3]} | | | | | {sys.argv[4]} | {sys.argv[5]} | | {status} |")
    sys.exit()
dt = r["simulated_time"] / r["steps"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {r['particles']} | {r['settle_steps']} | {r['steps']} | {dt:.2e} | "
      f"{sys.argv[4]} | {sys.argv[5]} | {r['mfr']:.3f} | {status} |")
PY
done
