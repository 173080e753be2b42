#!/usr/bin/env bash
# Thread scaling: the standard jobs rendered at several thread counts, thread counts taken in
# turn within each round (1, 2, 4, …, then again) so that a drifting machine affects them alike.
# For each job it prints the median wall time, the speed-up over one thread, the parallel
# utilisation that `--stats` reports (`parallel`) and Amdahl's bound from the one-thread run;
# then, per wavefront stage, the speed-up of the stage's time and its utilisation at the most
# threads. On a machine with few cores the utilisation and the bound are what tell how a render
# would scale on many (BENCHMARKS.md, "Scaling").
#
#   bash benches/scaling.sh [THREADS...]                 # default: 1 2 4 … up to nproc
#   ROUNDS=3 JOBS=spheres,hall PW=target/release/photonwave bash benches/scaling.sh 1 2
#
# Jobs: spheres (cornell-spheres, one pass at the defaults), spheres16 (its --passes 16),
# spheres160 and spheres160-ref (160², wavefront and reference engines), table (table.toml at
# 960×720), hall and hall-ref (../shared/scenes/modern-hall at 128², where present).
# Keeps every run's --stats JSON in $OUT (default benches/scaling-out/, not committed).
set -euo pipefail
cd "$(dirname "$0")/.."
pw=${PW:-target/release/photonwave}
[ -x "$pw" ] || cargo build --release --quiet
rounds=${ROUNDS:-1}
out=${OUT:-benches/scaling-out}
mkdir -p "$out"
if [ $# -gt 0 ]; then
  threads=("$@")
else
  threads=()
  for t in 1 2 4 8 16 32 64; do [ "$t" -le "$(nproc)" ] && threads+=("$t"); done
fi
hall=../shared/scenes/modern-hall/scene.toml
declare -A args=(
  [spheres]="scenes/cornell-spheres.toml"
  [spheres16]="scenes/cornell-spheres.toml --passes 16"
  [spheres160]="scenes/cornell-spheres.toml --width 160 --height 160"
  [spheres160-ref]="scenes/cornell-spheres.toml --width 160 --height 160 --engine reference"
  [table]="scenes/table.toml --width 960 --height 720"
  [hall]="$hall --width 128 --height 128"
  [hall-ref]="$hall --width 128 --height 128 --engine reference"
)
IFS=, read -r -a jobs <<<"${JOBS:-spheres,spheres16,spheres160,spheres160-ref,table,hall,hall-ref}"
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
echo "machine: $(nproc) cores, $cpu; binary: $pw; rounds: $rounds"
for job in "${jobs[@]}"; do
  [ -n "${args[$job]:-}" ] || { echo "unknown job $job" >&2; exit 2; }
  case $job in hall*) [ -f "$hall" ] || { echo "$job: skipped ($hall not found)"; continue; } ;; esac
  for round in $(seq 1 "$rounds"); do
    for t in "${threads[@]}"; do
      # shellcheck disable=SC2086
      "$pw" render ${args[$job]} --threads "$t" -q -o "$out/$job.exr" --stats "$out/$job-t$t-r$round.json"
    done
  done
done
python3 - "$out" "${threads[*]}" "${jobs[*]}" <<'PY'
import glob, json, statistics, sys
out, threads, jobs = sys.argv[1], [int(t) for t in sys.argv[2].split()], sys.argv[3].split()
def runs(job, t):
    return [json.load(open(f)) for f in sorted(glob.glob(f"{out}/{job}-t{t}-r*.json"))]
for job in jobs:
    if not runs(job, threads[0]):
        continue
    print(f"\n{job}")
    print("threads  wall s  speed-up  utilisation  outside s  Amdahl bound at 16")
    base = None
    for t in threads:
        rs = runs(job, t)
        wall = statistics.median(r["times"]["total_s"] for r in rs)
        p = [r.get("parallel") or {} for r in rs]
        util = statistics.median(x.get("utilisation", 0) for x in p)
        outside = statistics.median(x.get("outside_regions_s", 0) for x in p)
        busy = statistics.median(x.get("busy_s", 0) for x in p)
        bound = (outside + busy) / (outside + busy / 16) if outside + busy > 0 else 1
        base = base or wall
        print(f"{t:7d} {wall:7.2f} {base / wall:9.2f} {100 * util:11.0f} % {outside:9.2f} {bound:12.1f}")
    first, last = runs(job, threads[0]), runs(job, threads[-1])
    if not first[0].get("stages"):
        continue
    # Stages that share their lanes among the threads (the photon pass's) have a wall time of
    # their own: its speed-up and utilisation are printed. Stages run inside each worker's own
    # tiles (the camera pass's) report the time summed over the workers: printed is that sum's
    # growth from the fewest to the most threads (1.00 = no contention; above 1 = the workers
    # slow each other down: memory bandwidth, shared caches, hyper-threads).
    print(f"stage (seconds at {threads[0]} and {threads[-1]} threads, speed-up and utilisation at {threads[-1]}"
          f" for shared stages; worker-seconds and their growth for per-worker stages)")
    stages = first[0]["stages"]
    for name in sorted(stages, key=lambda n: -stages[n]["seconds"]):
        if not all(name in r["stages"] for r in first + last):
            continue
        a = statistics.median(r["stages"][name]["seconds"] for r in first)
        b = statistics.median(r["stages"][name]["seconds"] for r in last)
        busy = statistics.median(r["stages"][name].get("busy_seconds", 0) for r in last)
        if abs(busy - b) <= 1e-9 * max(b, 1) and threads[-1] > 1:
            print(f"  {name:20s} {a:7.3f} {b:7.3f} per worker, grew {b / a if a else 0:5.2f}x")
        else:
            util = busy / (threads[-1] * b) if b > 0 else 0
            print(f"  {name:20s} {a:7.3f} {b:7.3f} {a / b if b else 0:6.2f}x {100 * util:5.0f} %")
PY
