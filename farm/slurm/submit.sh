#!/usr/bin/env bash
# Submit a photonwave render to Slurm: an array job of render tasks, each
# rendering its own set of progressive passes, and a merge job that runs
# after all of them have succeeded. Run with --help for the usage.
set -euo pipefail

HERE=$(cd -- "$(dirname -- "$(readlink -f -- "${BASH_SOURCE[0]}")")" && pwd)
REPO=$(cd -- "$HERE/../.." && pwd)
PROG=$(basename -- "$0")

usage() {
    cat <<EOF
Usage: $PROG [OPTIONS] SCENE OUTDIR TASKS [PASSES] [-- RENDER_FLAGS...]

Render SCENE on a Slurm cluster as TASKS array tasks, then merge their parts.
Task K (0 <= K < TASKS) renders progressive passes K, K+TASKS, K+2*TASKS, ...
into OUTDIR/parts/part-K.exr; the merge job sums the parts exactly into
OUTDIR/NAME.exr, NAME.png and NAME.json.

Arguments:
  SCENE    scene file (.toml, or .obj with its .mtl)
  OUTDIR   output folder, created with parts/, checkpoints/ and logs/
  TASKS    number of array tasks (pass sets)
  PASSES   total passes over all tasks; the merged image equals
           'photonwave render SCENE --passes PASSES RENDER_FLAGS' bit for bit
  RENDER_FLAGS  more render flags for every task, e.g. --width 640 --seed 3
           (not -o, --passes, --time, --pass-set, --checkpoint*, --resume)

Options:
  --time DUR        time budget per task (render --time, e.g. 30m), instead of
                    PASSES or as well (a task stops at whichever comes first)
  --wall TIME       Slurm time limit of each render task (sbatch --time,
                    e.g. 2:00:00); the renderer is told to stop 60 s before it
  --cpus N          CPUs per render task (sbatch --cpus-per-task; the renderer
                    then uses N threads)
  --partition P     Slurm partition for both jobs
  --max-running N   run at most N render tasks at once (--array=...%N)
  --array LIST      submit only these task indices, e.g. 3 or 0,4-5, to redo
                    failed or cut-short tasks; implies --resume
  --resume          allow an OUTDIR that already holds parts or checkpoints:
                    each task continues from its own (same scene and flags!)
  --checkpoint-every DUR
                    how often a task saves its checkpoint [renderer default]
  --name NAME       name of the merged files [SCENE's file name without extension]
  --photonwave PATH renderer binary, as the compute nodes see it
                    [\$PHOTONWAVE, else $REPO/target/release/photonwave,
                    else photonwave on PATH]
  --sbatch ARG      one more argument for sbatch, for both jobs (repeatable),
                    e.g. --sbatch=--account=myproj
  --complete        make the merge fail, instead of warning, when passes are
                    missing (a task that failed or stopped early)
  --no-merge        submit the render tasks only
  -h, --help        show this help

sbatch also reads its SBATCH_* environment variables (SBATCH_PARTITION,
SBATCH_ACCOUNT, ...). Prints the job ids as render_job=ID and merge_job=ID.

Examples:
  $PROG scenes/cornell-box.toml /scratch/box 8 256 -- --width 640 --height 640
  $PROG --time 50m --wall 1:00:00 --cpus 16 scenes/cornell-spheres.toml /scratch/sph 32
  $PROG --array 5 --wall 2:00:00 scenes/cornell-box.toml /scratch/box 8 256 -- --width 640 --height 640
EOF
}

die() {
    echo "$PROG: error: $*" >&2
    exit 2
}

need_value() { [[ $# -ge 2 && -n $2 ]] || die "$1 needs a value (see --help)"; }

is_uint() { [[ $1 =~ ^[0-9]+$ ]]; }

# A whole number >= 1, or exit with MESSAGE.
positive() {
    if ! is_uint "$1" || (($1 < 1)); then die "$2"; fi
}

budget='' wall='' cpus='' partition='' max_running='' array='' every='' name=''
resume=0 merge=1 complete=0 pw=${PHOTONWAVE:-}
sbatch_extra=()
positional=()
flags=()

while (($# > 0)); do
    case $1 in
        -h | --help) usage; exit 0 ;;
        --time) need_value "$@"; budget=$2; shift 2 ;;
        --time=*) budget=${1#*=}; shift ;;
        --wall) need_value "$@"; wall=$2; shift 2 ;;
        --wall=*) wall=${1#*=}; shift ;;
        --cpus) need_value "$@"; cpus=$2; shift 2 ;;
        --cpus=*) cpus=${1#*=}; shift ;;
        --partition) need_value "$@"; partition=$2; shift 2 ;;
        --partition=*) partition=${1#*=}; shift ;;
        --max-running) need_value "$@"; max_running=$2; shift 2 ;;
        --max-running=*) max_running=${1#*=}; shift ;;
        --array) need_value "$@"; array=$2; resume=1; shift 2 ;;
        --array=*) array=${1#*=}; resume=1; shift ;;
        --resume) resume=1; shift ;;
        --checkpoint-every) need_value "$@"; every=$2; shift 2 ;;
        --checkpoint-every=*) every=${1#*=}; shift ;;
        --name) need_value "$@"; name=$2; shift 2 ;;
        --name=*) name=${1#*=}; shift ;;
        --photonwave) need_value "$@"; pw=$2; shift 2 ;;
        --photonwave=*) pw=${1#*=}; shift ;;
        --sbatch) need_value "$@"; sbatch_extra+=("$2"); shift 2 ;;
        --sbatch=*) sbatch_extra+=("${1#*=}"); shift ;;
        --no-merge) merge=0; shift ;;
        --complete) complete=1; shift ;;
        --) shift; flags=("$@"); break ;;
        -*) die "unknown option: $1 (render flags go after --; see --help)" ;;
        *) positional+=("$1"); shift ;;
    esac
done

((${#positional[@]} >= 3 && ${#positional[@]} <= 4)) || {
    usage >&2
    exit 2
}
scene=${positional[0]} outdir=${positional[1]} tasks=${positional[2]} passes=${positional[3]:-}

[[ -f $scene ]] || die "scene file not found: $scene"
scene=$(readlink -f -- "$scene")
positive "$tasks" "TASKS must be a whole number >= 1, not '$tasks'"
if [[ -n $passes ]]; then
    positive "$passes" "PASSES must be a whole number >= 1, not '$passes'"
    ((tasks <= passes)) || die "$tasks tasks for $passes passes: some tasks would have no pass; use at most $passes tasks"
fi
[[ -n $passes || -n $budget ]] || die "give PASSES, --time DUR, or both (see --help)"
[[ -z $cpus ]] || positive "$cpus" "--cpus needs a whole number >= 1, not '$cpus'"
[[ -z $max_running ]] || positive "$max_running" "--max-running needs a whole number >= 1, not '$max_running'"

for f in "${flags[@]}"; do
    case $f in
        -o | --output | --output=* | --passes | --passes=* | --time | --time=* | --pass-set | --pass-set=* | \
            --checkpoint | --checkpoint=* | --checkpoint-every | --checkpoint-every=* | --resume | --resume=*)
            die "render flag $f is set by the farm scripts; use the arguments and options of $PROG instead" ;;
    esac
done

# The renderer.
if [[ -z $pw ]]; then
    if [[ -x $REPO/target/release/photonwave ]]; then
        pw=$REPO/target/release/photonwave
    else
        pw=$(command -v photonwave) || die "no photonwave binary found: build it or pass --photonwave PATH"
    fi
elif [[ $pw != */* ]]; then
    pw=$(command -v -- "$pw") || die "renderer not found on PATH: $pw"
fi
[[ $pw == /* ]] || pw=$(readlink -f -- "$pw")
if [[ -x $pw ]]; then
    help=$("$pw" render --help 2>/dev/null) || help=
    [[ $help == *--pass-set* ]] || die "$pw does not know 'render --pass-set': rebuild it (cargo build --release)"
else
    echo "$PROG: warning: $pw is not executable here; hoping the compute nodes have it" >&2
fi

# The output folders: Slurm does not create them, and a job whose --output
# folder is missing fails to start.
mkdir -p "$outdir"
outdir=$(readlink -f -- "$outdir")
if ((!resume)); then
    shopt -s nullglob
    old=("$outdir"/parts/*.exr "$outdir"/checkpoints/*.exr)
    shopt -u nullglob
    ((${#old[@]} == 0)) ||
        die "$outdir already holds parts or checkpoints of an earlier run; use an empty folder, or --resume to continue them"
fi
mkdir -p "$outdir/parts" "$outdir/checkpoints" "$outdir/logs"

if [[ -z $name ]]; then
    name=$(basename -- "$scene")
    name=${name%.*}
fi
[[ -n $array ]] || array=0-$((tasks - 1))
[[ -z $max_running ]] || array+=%$max_running

# RENDER_FLAGS: one string, each flag quoted so that render.sbatch splits it
# back (with xargs) into the same words.
render_flags=
quote="'\\''" # ends a quoted word, adds an escaped ', starts a new one
for f in "${flags[@]}"; do
    if [[ $f =~ ^[A-Za-z0-9_./,:=+-]+$ ]]; then
        render_flags+=" $f"
    else
        render_flags+=" '${f//\'/$quote}'"
    fi
done
render_flags=${render_flags# }

# The jobs read their settings from the environment (sbatch --export=ALL).
# Unset what is not given, so that a stale value in the caller's shell does
# not leak into the jobs.
export PHOTONWAVE=$pw SCENE=$scene OUTDIR=$outdir TASKS=$tasks NAME=$name RENDER_FLAGS=$render_flags
unset PASSES BUDGET CHECKPOINT_EVERY MERGE_FLAGS
[[ -z $passes ]] || export PASSES=$passes
[[ -z $budget ]] || export BUDGET=$budget
[[ -z $every ]] || export CHECKPOINT_EVERY=$every
((!complete)) || export MERGE_FLAGS=--complete

common=(--parsable --export=ALL --chdir="$outdir")
[[ -z $partition ]] || common+=(--partition="$partition")
common+=("${sbatch_extra[@]}")

render_args=("${common[@]}" --array="$array" --job-name="pw-$name" --output="$outdir/logs/render-%A_%a.out")
[[ -z $wall ]] || render_args+=(--time="$wall")
[[ -z $cpus ]] || render_args+=(--cpus-per-task="$cpus")

render_job=$(sbatch "${render_args[@]}" "$HERE/render.sbatch")
render_job=${render_job%%;*}
echo "render_job=$render_job"
echo "$PROG: render tasks $array of $tasks: job $render_job, logs in $outdir/logs/" >&2

if ((merge)); then
    merge_job=$(sbatch "${common[@]}" --dependency="afterok:$render_job" --kill-on-invalid-dep=yes \
        --job-name="pw-$name-merge" --output="$outdir/logs/merge-%j.out" "$HERE/merge.sbatch") || {
        echo "$PROG: error: the merge job was not submitted; the render job $render_job runs anyway" \
            "(scancel $render_job to stop it)" >&2
        exit 1
    }
    merge_job=${merge_job%%;*}
    echo "merge_job=$merge_job"
    echo "$PROG: merge job $merge_job runs after every task of $render_job succeeds: $outdir/$name.exr" >&2
fi
