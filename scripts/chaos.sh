#!/usr/bin/env bash
# Kill-and-resume chaos test (README "Reliability"; BENCHMARKS.md "Chaos").
#
#   bash scripts/chaos.sh [KILLS] [POINTS] [JOBS]      (defaults 32, 16, 2)
#
#   ENGINE=stand-in   run the stand-in engine instead of LIGGGHTS (for storms of 10,000 points)
#   WORKERS=3         that many `sweep` processes work on the same directory at once
#   KEEP=1            keep the work directory;  SWEEP=path  the binary (default target/release/sweep)
#   WARM=0            start every LIGGGHTS run from rest (default: warm starts on)
#
# Runs a small LDS sweep once without interruption (the reference), then again in another
# directory under a storm: WORKERS processes (`sweep lds`, then `sweep resume`) work on it at
# once, and KILLS times one of them, chosen at random, is signalled and started again. Every
# other signal comes right after a run finishes (a new result.json, LIGGGHTS) or a new joblog
# line (the stand-in); the others at a random moment. Nine in ten signals are SIGKILL, the rest
# SIGTERM or SIGINT. A last `sweep resume` finishes the sweep. It then checks and prints:
#   - non-zero exits: a worker that ended by itself with an error (must be 0);
#   - runs executed twice: hashes with more than one `done` line in the joblog (0);
#   - attempts without a joblog line: result.json files with no `done` line (0);
#   - stale claims: claim files left in run directories at the end (0);
#   - orphans: LIGGGHTS processes in the sweep directory whose ancestors include no live worker,
#     2 s after each signal and at the end (0);
#   - results.csv equal to the reference's, every column but runtime_s (with warm starts: the
#     same hashes, values and statuses, and every MFR within 4 combined SE of the reference's).
# Exit 0 when all hold. Needs the release binary (cargo build --release) and, unless
# ENGINE=stand-in, LIGGGHTS (scripts/setup.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
KILLS=${1:-32}
POINTS=${2:-16}
JOBS=${3:-2}
WORKERS=${WORKERS:-1}
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
[ "${ENGINE:-}" = stand-in ] && printf '[run]\nengine = "stand-in"\n' >>"$work/chaos.toml"
if [ "${WARM:-1}" = 0 ]; then warm=false; else warm=true; fi
printf '[scene]\nwarm_start = %s\n' "$warm" >>"$work/chaos.toml"
lds=(lds "$work/chaos.toml" --max "$POINTS" --step "$POINTS" --jobs "$JOBS" -q)

echo "chaos: reference sweep of $POINTS points ($JOBS jobs, engine ${ENGINE:-liggghts})"
t0=$(date +%s.%N)
"$SWEEP" "${lds[@]}" --out "$work/ref" 2>/dev/null
took=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
# Longest wait before a random signal: 1.5 times the time one slot took per run, at least 0.05 s
# for the stand-in (its runs take microseconds) and 3 s for LIGGGHTS.
floor=3; [ "${ENGINE:-}" = stand-in ] && floor=0.05
wait_max=$(awk -v t="$took" -v j="$JOBS" -v n="$POINTS" -v f="$floor" \
  'BEGIN { w = 1.5 * t * j / n; printf "%.2f", (w < f ? f : w) }')
echo "chaos: reference took $took s; random signals come up to $wait_max s after the last"

out="$work/chaos"
kills=0 starts=0 orphans=0 refused=0 after_result=0
declare -A pid_of=()   # worker slot -> pid

# Finished runs so far: result.json files (LIGGGHTS) or joblog lines (the stand-in, whose 10,000
# run directories are too many to list every few milliseconds).
finished() {
  if [ "${ENGINE:-}" = stand-in ]; then
    [ -f "$out/joblog.tsv" ] && wc -l <"$out/joblog.tsv" || echo 0
  else
    { compgen -G "$out/runs/*/result.json" || true; } | wc -l
  fi
}
# LIGGGHTS processes working in the chaos directory with no live worker among their ancestors
# (a process that ends while it is looked at is not counted).
orphans_now() {
  local n=0 p pid a live ppid
  for p in /proc/[0-9]*; do
    case "$(readlink "$p/cwd" 2>/dev/null)" in "$out"/*) ;; *) continue ;; esac
    pid=${p#/proc/}; live=0; a=$pid
    while [ "$a" -gt 1 ]; do
      for w in "${pid_of[@]}"; do [ "$a" = "$w" ] && live=1; done
      ppid=$(awk '{ print $4 }' "/proc/$a/stat" 2>/dev/null || true)
      [ -n "$ppid" ] || { live=gone; break; }
      a=$ppid
    done
    [ "$live" = 0 ] && [ -d "$p" ] && n=$((n + 1))
  done
  echo "$n"
}
start_worker() { # slot
  local cmd
  if [ -f "$out/manifest.json" ]; then cmd=(resume "$out" --jobs "$JOBS" -q); else cmd=("${lds[@]}" --out "$out"); fi
  "$SWEEP" "${cmd[@]}" 2>>"$work/stderr" &
  pid_of[$1]=$!
  starts=$((starts + 1))
}
# Reap worker slots that ended by themselves; complete=yes once one of them finished the sweep.
complete=no
reap_ended() {
  local s rc
  for s in "${!pid_of[@]}"; do
    kill -0 "${pid_of[$s]}" 2>/dev/null && continue
    rc=0; wait "${pid_of[$s]}" 2>/dev/null || rc=$?
    unset "pid_of[$s]"
    if [ "$rc" = 0 ]; then complete=yes; else refused=$((refused + 1)); echo "chaos: a worker exited $rc" >&2; fi
  done
}

# The first worker makes the directory alone; the others join once its manifest is written.
start_worker 0
for _ in $(seq 200); do [ -f "$out/manifest.json" ] && break; sleep 0.05; done
for s in $(seq 1 $((WORKERS - 1))); do start_worker "$s"; done
while [ "$kills" -lt "$KILLS" ]; do
  if [ $((kills % 2)) = 0 ]; then
    # Right after a run finishes.
    before=$(finished)
    # Give up after four random waits' worth of 10 ms polls.
    polls=$(awk -v m="$wait_max" 'BEGIN { printf "%d", m * 400 }')
    while [ "$(finished)" = "$before" ] && [ "$polls" -gt 0 ]; do sleep 0.01; polls=$((polls - 1)); done
    after_result=$((after_result + 1))
  else
    sleep "$(awk -v r="$RANDOM" -v m="$wait_max" 'BEGIN { printf "%.3f", m * r / 32767 }')"
  fi
  reap_ended
  [ "$complete" = yes ] && break
  slots=("${!pid_of[@]}")
  [ ${#slots[@]} -gt 0 ] || break
  slot=${slots[$((RANDOM % ${#slots[@]}))]}
  r=$((RANDOM % 20))
  sig=KILL; [ "$r" = 0 ] && sig=TERM; [ "$r" = 1 ] && sig=INT
  kill -s "$sig" "${pid_of[$slot]}" 2>/dev/null || true
  rc=0; wait "${pid_of[$slot]}" 2>/dev/null || rc=$?
  unset "pid_of[$slot]"
  # An interrupted sweep exits 130 (SIGINT) or 143 (SIGTERM); KILL gives 137; 0 if it had finished.
  case "$rc" in 0|130|137|143) ;; *) refused=$((refused + 1)); echo "chaos: a worker exited $rc after SIG$sig" >&2 ;; esac
  kills=$((kills + 1))
  if [ "${ENGINE:-}" != stand-in ]; then
    sleep 2
    left=$(orphans_now)
    orphans=$((orphans + left))
    printf 'chaos: signal %d/%d (SIG%s), %s orphans\n' "$kills" "$KILLS" "$sig" "$left"
  fi
  start_worker "$slot"
done
for s in "${!pid_of[@]}"; do
  rc=0; wait "${pid_of[$s]}" || rc=$?
  [ "$rc" = 0 ] || { refused=$((refused + 1)); echo "chaos: a worker exited $rc" >&2; }
done
pid_of=()
between=$(awk -F'\t' 'NR > 1 && $12 == "done"' "$out/joblog.tsv" 2>/dev/null | wc -l)
echo "chaos: $kills signals ($after_result right after a run) in $starts starts of $WORKERS workers; $between of $POINTS runs done before the last resume"
"$SWEEP" resume "$out" --jobs "$JOBS" -q 2>/dev/null
[ "${ENGINE:-}" = stand-in ] || orphans=$((orphans + $(orphans_now)))

# joblog.tsv: Status is column 12 and Hash column 11 (GNU parallel's nine columns, then Index).
twice=$(awk -F'\t' 'NR > 1 && $12 == "done" { n[$11]++ } END { t = 0; for (h in n) if (n[h] > 1) t++; print t }' "$out/joblog.tsv")
attempts=$(awk -F'\t' 'NR > 1' "$out/joblog.tsv" | wc -l)
nodup=$(awk -F'\t' 'NR > 1 { print $1 }' "$out/joblog.tsv" | sort | uniq -d | wc -l)
results=$(find "$out/runs" -name result.json | wc -l)
logged=$(awk -F'\t' 'NR > 1 && $12 == "done" { n[$11] = 1 } END { print length(n) }' "$out/joblog.tsv")
unlogged=$((results - logged))
claims=$(find "$out/runs" -name claim | wc -l)
strip() { # results.csv without the runtime_s column
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "runtime_s") c = i }
           { s = ""; for (i = 1; i <= NF; i++) if (i != c) s = s (s == "" ? "" : ",") $i; print s }' "$1"
}
# A warm-started run begins from whichever neighbour had finished, so its numbers are the same
# measurement of the same point, not the same digits: with warm starts, each point must have the
# reference's hash, values and status, and an MFR within 4 combined standard errors of it.
warm_equal() {
  python3 - "$1" "$2" <<'PY'
import csv, math, sys
ref, got = ([r for r in csv.DictReader(open(f))] for f in sys.argv[1:3])
ok = len(ref) == len(got)
for a, b in zip(ref, got):
    keys = [k for k in a if k not in ("runtime_s",) and not k.startswith(("mfr", "vx_", "layer", "covered", "roughness", "steady", "stop", "quality"))]
    ok &= all(a[k] == b[k] for k in keys)
    if a["mfr"] and b["mfr"]:
        se = math.hypot(float(a["mfr_se"] or 0), float(b["mfr_se"] or 0))
        ok &= abs(float(a["mfr"]) - float(b["mfr"])) <= 4 * se + 1e-12
sys.exit(0 if ok else 1)
PY
}
if [ "${WARM:-1}" = 1 ] && [ "${ENGINE:-}" != stand-in ]; then
  if warm_equal "$work/ref/results.csv" "$out/results.csv"; then same=yes; else same=no; fi
elif diff <(strip "$work/ref/results.csv") <(strip "$out/results.csv") >/dev/null; then same=yes; else same=no; fi
echo "chaos: $attempts attempts in the joblog (repeated seq: $nodup); $results results"
echo "chaos: runs executed twice: $twice; attempts without a joblog line: $unlogged; stale claims: $claims; orphans: $orphans; non-zero exits: $refused; results equal to the reference: $same"
[ "$twice" = 0 ] && [ "$unlogged" = 0 ] && [ "$claims" = 0 ] && [ "$orphans" = 0 ] && [ "$refused" = 0 ] \
  && [ "$nodup" = 0 ] && [ "$same" = yes ]
