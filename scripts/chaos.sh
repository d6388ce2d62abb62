#!/usr/bin/env bash
# Kill-and-resume chaos test on a real LIGGGHTS sweep (README "Reliability").
#
#   bash scripts/chaos.sh [KILLS] [POINTS] [JOBS]      (defaults 32, 16, 2)
#
# Runs a small LDS sweep of the quick scene once without interruption (the reference), then
# again in another directory while SIGKILLing `sweep lds` / `sweep resume` at random moments
# (0.5 s to 1.5 times the reference's time per run after each start, so that some runs finish
# between kills and others are cut off) KILLS times, resuming after each kill, and finally lets
# a resume finish. It then checks and prints:
#   - kills survived: every resume after a kill ran (exit 0 or killed again), none refused;
#   - runs executed twice: hashes with more than one `done` line in the joblog (must be 0);
#   - orphans: LIGGGHTS processes still running in the sweep directory 2 s after a kill (0);
#   - results.csv equal to the reference's, every column but runtime_s.
# Exit 0 when all hold. Needs the release binary (cargo build --release) and LIGGGHTS
# (scripts/setup.sh). SWEEP=path overrides the binary; KEEP=1 keeps the work directory.
set -euo pipefail
cd "$(dirname "$0")/.."
KILLS=${1:-32}
POINTS=${2:-16}
JOBS=${3:-2}
SWEEP=${SWEEP:-target/release/sweep}
[ -x "$SWEEP" ] || { echo "chaos: $SWEEP not found; run cargo build --release" >&2; exit 2; }
work=$(mktemp -d /tmp/sweep-chaos.XXXXXX)
[ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$work"' EXIT
cat >"$work/chaos.toml" <<'EOF'
name = "chaos"
[parameters]
gap         = { lo = 2.0, hi = 3.0, unit = "mm" }
blade_speed = { lo = 1.2, hi = 1.6, unit = "m/s" }
diameter    = { value = 1.5, unit = "mm" }
EOF
lds=(lds "$work/chaos.toml" --max "$POINTS" --step "$POINTS" --jobs "$JOBS" -q)

echo "chaos: reference sweep of $POINTS points ($JOBS jobs)"
t0=$(date +%s)
"$SWEEP" "${lds[@]}" --out "$work/ref"
took=$(( $(date +%s) - t0 ))
# Longest wait before a kill: 1.5 times the time one slot took per run (at least 3 s).
wait_max=$(awk -v t="$took" -v j="$JOBS" -v n="$POINTS" 'BEGIN { w = 1.5 * t * j / n; printf "%.1f", (w < 3 ? 3 : w) }')
echo "chaos: reference took $took s; kills come 0.5 to $wait_max s after each start"

out="$work/chaos"
kills=0 starts=0 orphans=0 refused=0
# LIGGGHTS processes working in the chaos directory.
in_out() {
  local n=0 p
  for p in /proc/[0-9]*; do
    case "$(readlink "$p/cwd" 2>/dev/null)" in "$out"/*) n=$((n + 1)) ;; esac
  done
  echo "$n"
}
while [ "$kills" -lt "$KILLS" ]; do
  if [ -f "$out/manifest.json" ]; then cmd=(resume "$out" --jobs "$JOBS" -q); else cmd=("${lds[@]}" --out "$out"); fi
  "$SWEEP" "${cmd[@]}" 2>>"$work/stderr" &
  pid=$!
  starts=$((starts + 1))
  sleep "$(awk -v r="$RANDOM" -v m="$wait_max" 'BEGIN { printf "%.2f", 0.5 + (m - 0.5) * r / 32767 }')"
  if kill -0 "$pid" 2>/dev/null; then
    kill -9 "$pid"
    wait "$pid" 2>/dev/null || true
    kills=$((kills + 1))
    sleep 2
    left=$(in_out)
    orphans=$((orphans + left))
    printf 'chaos: kill %d/%d (%s), %s LIGGGHTS left behind\n' "$kills" "$KILLS" "${cmd[0]}" "$left"
  else
    rc=0
    wait "$pid" || rc=$?
    if [ "$rc" != 0 ]; then refused=$((refused + 1)); echo "chaos: ${cmd[0]} exited $rc" >&2; fi
    # Finished before the kill: the sweep is complete, so the remaining kills cannot happen.
    [ "$rc" = 0 ] && break
  fi
done
# joblog.tsv: Status is column 12 and Hash column 11 (GNU parallel's nine columns, then Index).
between=$(awk -F'\t' 'NR > 1 && $12 == "done"' "$out/joblog.tsv" 2>/dev/null | wc -l)
echo "chaos: $between of $POINTS runs finished between kills; final resume"
"$SWEEP" resume "$out" --jobs "$JOBS" -q

twice=$(awk -F'\t' 'NR > 1 && $12 == "done" { n[$11]++ } END { t = 0; for (h in n) if (n[h] > 1) t++; print t }' "$out/joblog.tsv")
attempts=$(awk -F'\t' 'NR > 1' "$out/joblog.tsv" | wc -l)
nodup=$(awk -F'\t' 'NR > 1 { print $1 }' "$out/joblog.tsv" | sort | uniq -d | wc -l)
strip() { # results.csv without the runtime_s column
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "runtime_s") c = i }
           { s = ""; for (i = 1; i <= NF; i++) if (i != c) s = s (s == "" ? "" : ",") $i; print s }' "$1"
}
if diff <(strip "$work/ref/results.csv") <(strip "$out/results.csv") >/dev/null; then same=yes; else same=no; fi
echo "chaos: $kills kills in $starts starts; $attempts attempts in the joblog (repeated seq: $nodup)"
echo "chaos: runs executed twice: $twice; orphans: $orphans; non-zero exits: $refused; results equal to the reference: $same"
[ "$twice" = 0 ] && [ "$orphans" = 0 ] && [ "$refused" = 0 ] && [ "$nodup" = 0 ] && [ "$same" = yes ]
