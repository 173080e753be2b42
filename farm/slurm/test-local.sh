#!/usr/bin/env bash
# End-to-end test of the Slurm farm scripts on one Debian machine, as root.
#
# Installs Slurm and MUNGE if they are missing, starts munged (unless a
# working one runs), slurmctld and slurmd by hand with a private
# configuration in a temporary folder, submits renders through submit.sh and
# checks that the merged images equal local renders bit for bit:
#
#   split      TASKS=3 array tasks share PASSES=7 passes; the merge must equal
#              `photonwave render SCENE --passes 7` (cmp)
#   failure    a task that fails must get the merge job cancelled, not left
#              waiting (afterok + kill_invalid_depend)
#   interrupt  a task sent SIGTERM mid-render saves its passes and counts as a
#              success; the merge warns and writes a short image; the task is
#              resubmitted with --array, continues from its checkpoint, and the
#              new merge equals the undivided render (cmp)
#   budget     tasks with --time instead of PASSES run and merge
#   walltime   (slow, ~2 min; not run unless named in TESTS) tasks with a
#              2-minute Slurm time limit and a longer --time budget get
#              SIGTERM from Slurm (--signal=B:TERM@60), save their passes,
#              complete, and the merge runs
#
# Then it stops the daemons it started (and only those) and deletes its
# temporary folder (kept on failure, for the logs).
#
# Usage: farm/slurm/test-local.sh            (from any folder)
# Environment:
#   PHOTONWAVE  renderer binary [REPO/target/release/photonwave, built with
#               `cargo build --release` if missing]
#   SCENE       scene [REPO/scenes/cornell-box.toml]
#   TESTS       which tests, space-separated [split failure interrupt budget]
#   KEEP=1      keep the temporary folder even on success
#   TIMEOUT     seconds to wait for the jobs of one test [300]
set -euo pipefail

HERE=$(cd -- "$(dirname -- "$(readlink -f -- "${BASH_SOURCE[0]}")")" && pwd)
REPO=$(cd -- "$HERE/../.." && pwd)
SUBMIT=$HERE/submit.sh

PHOTONWAVE=${PHOTONWAVE:-$REPO/target/release/photonwave}
SCENE=${SCENE:-$REPO/scenes/cornell-box.toml}
TESTS=${TESTS:-split failure interrupt budget}
KEEP=${KEEP:-0}
TIMEOUT=${TIMEOUT:-300}
# Small renders: a pass takes some tens of milliseconds.
FLAGS=(--width 64 --height 64 --spp 1 --photons 5000 --caustic-photons 5000 --seed 7)
PACKAGES=(slurmctld slurmd slurm-client slurm-wlm-basic-plugins munge)
PREFIX=/tmp/photonwave-slurm-test.
LOCK=/run/lock/photonwave-slurm-test.lock

passed=0
failed=0
WORK=
created_policy=0
started_munged=
t_start=$EPOCHREALTIME

# since T0: seconds since T0 (an EPOCHREALTIME), with one decimal
since() { awk -v a="$EPOCHREALTIME" -v b="$1" 'BEGIN { printf "%.1f", a - b }'; }
log() { printf '[%6ss] %s\n' "$(since "$t_start")" "$*"; }
die() {
    echo "test-local: error: $*" >&2
    exit 1
}
ok() {
    passed=$((passed + 1))
    echo "  ok   - $*"
}
bad() {
    failed=$((failed + 1))
    echo "  FAIL - $*"
}
check() { # check DESCRIPTION COMMAND...: ok if COMMAND succeeds
    local what=$1
    shift
    if "$@"; then ok "$what"; else bad "$what"; fi
}

# ---------------------------------------------------------------------------
# Daemons, by pid file. A pid file names our daemon only if that pid is alive,
# not a zombie (a killed daemon lingers as one for a while here), has the
# right name and, for the Slurm daemons, was started with our configuration.

# daemon_pid PIDFILE NAME [TEXT]: print the pid if PIDFILE names a live
# process called NAME whose command line contains TEXT.
daemon_pid() {
    local file=$1 name=$2 text=${3:-} pid stat state cmd
    [[ -r $file ]] || return 1
    read -r pid <"$file" 2>/dev/null || return 1
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    stat=$(cat "/proc/$pid/stat" 2>/dev/null) || return 1
    state=${stat##*) }
    state=${state%% *}
    [[ $state != [ZX] ]] || return 1
    [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$name" ]] || return 1
    if [[ -n $text ]]; then
        cmd=$(tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null) || return 1
        [[ $cmd == *"$text"* ]] || return 1
    fi
    echo "$pid"
}

# gone PID: true once PID has exited (or is a zombie waiting to be reaped).
gone() {
    local stat state
    stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 0
    state=${stat##*) }
    state=${state%% *}
    [[ $state == [ZX] ]]
}

# stop_daemon PIDFILE NAME [TEXT]: SIGTERM, then SIGKILL after 15 s.
stop_daemon() {
    local pid i
    pid=$(daemon_pid "$@") || return 0
    echo "test-local: stopping $2 (pid $pid)"
    kill -TERM "$pid" 2>/dev/null || return 0
    for ((i = 0; i < 150; i++)); do
        gone "$pid" && return 0
        sleep 0.1
    done
    echo "test-local: $2 (pid $pid) ignored SIGTERM; sending SIGKILL"
    kill -KILL "$pid" 2>/dev/null || true
}

# stop_cluster DIR: cancel the jobs of the cluster in DIR, stop its daemons.
stop_cluster() {
    local dir=$1 i jobs
    if daemon_pid "$dir/slurmctld.pid" slurmctld "$dir/slurm.conf" >/dev/null; then
        jobs=$(SLURM_CONF=$dir/slurm.conf squeue -h -o %A 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            echo "test-local: cancelling jobs $(echo "$jobs" | tr '\n' ' ')"
            # shellcheck disable=SC2086 # a list of job ids
            SLURM_CONF=$dir/slurm.conf scancel $jobs 2>/dev/null || true
            for ((i = 0; i < 300; i++)); do
                [[ -z $(SLURM_CONF=$dir/slurm.conf squeue -h -o %A 2>/dev/null) ]] && break
                sleep 0.1
            done
        fi
    fi
    stop_daemon "$dir/slurmd.pid" slurmd "$dir/slurm.conf"
    stop_daemon "$dir/slurmctld.pid" slurmctld "$dir/slurm.conf"
    # munged only if this run (or the earlier run that owned DIR) started it
    if [[ -s $dir/munged.started ]]; then
        local pid
        read -r pid <"$dir/munged.started"
        if [[ $(daemon_pid /run/munge/munged.pid munged || true) == "$pid" ]]; then
            stop_daemon /run/munge/munged.pid munged
        fi
        rm -f "$dir/munged.started"
    fi
}

cleanup() {
    local status=$?
    trap - EXIT INT TERM HUP
    trap '' PIPE # a closed output (| head) must not stop the cleanup
    set +e
    if [[ -n $WORK && -d $WORK ]]; then
        stop_cluster "$WORK"
        if ((status == 0 && failed == 0)) && [[ $KEEP != 1 ]]; then
            rm -rf "$WORK"
        else
            touch "$WORK/kept"
            echo "test-local: kept $WORK (logs: $WORK/log, job outputs: $WORK/*/logs)"
        fi
    fi
    if ((created_policy)) && [[ -e /usr/sbin/policy-rc.d ]]; then
        rm -f /usr/sbin/policy-rc.d
    fi
    exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
trap 'exit 129' HUP
trap 'exit 141' PIPE

# ---------------------------------------------------------------------------
# Preconditions

[[ $(id -u) == 0 ]] || die "run as root (it installs packages and starts daemons)"
command -v flock >/dev/null || die "flock (util-linux) is missing"
mkdir -p "$(dirname "$LOCK")"
exec 9>"$LOCK"
flock -n 9 || die "another test-local.sh is running (lock $LOCK)"

# Daemons and folders left by an earlier run that was killed before its
# cleanup ran (folders of failed runs, marked "kept", stay). We hold the lock,
# so no other run owns them.
for dir in "$PREFIX"*; do
    [[ -d $dir && -f $dir/slurm.conf ]] || continue
    stop_cluster "$dir"
    [[ -e $dir/kept ]] || rm -rf "$dir"
done

# The renderer.
if [[ ! -x $PHOTONWAVE ]]; then
    [[ $PHOTONWAVE == "$REPO/target/release/photonwave" ]] || die "PHOTONWAVE=$PHOTONWAVE is not an executable"
    command -v cargo >/dev/null || die "$PHOTONWAVE is missing and cargo is not installed"
    log "building $PHOTONWAVE (cargo build --release)"
    (cd "$REPO" && cargo build --release)
fi
help=$("$PHOTONWAVE" render --help 2>&1) || true
[[ $help == *--pass-set* ]] || die "$PHOTONWAVE has no 'render --pass-set': rebuild it (cargo build --release)"
"$PHOTONWAVE" merge --help >/dev/null 2>&1 || die "$PHOTONWAVE has no 'merge' command: rebuild it"
[[ -f $SCENE ]] || die "scene not found: $SCENE"

# ---------------------------------------------------------------------------
# Packages

missing=()
for p in "${PACKAGES[@]}"; do
    [[ $(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true) == installed ]] || missing+=("$p")
done
if ((${#missing[@]} > 0)); then
    command -v apt-get >/dev/null || die "missing ${missing[*]} and no apt-get (this script wants Debian)"
    # policy-rc.d exiting 101 keeps the packages' scripts from starting the
    # services: this test starts its own, with its own configuration.
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod 755 /usr/sbin/policy-rc.d
        created_policy=1
    fi
    log "installing ${missing[*]}"
    t0=$EPOCHREALTIME
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >"${TMPDIR:-/tmp}/photonwave-slurm-apt.log" 2>&1 ||
        die "apt-get update failed (see ${TMPDIR:-/tmp}/photonwave-slurm-apt.log)"
    apt-get install -y -q --no-install-recommends "${PACKAGES[@]}" >>"${TMPDIR:-/tmp}/photonwave-slurm-apt.log" 2>&1 ||
        die "apt-get install failed (see ${TMPDIR:-/tmp}/photonwave-slurm-apt.log)"
    if ((created_policy)); then
        rm -f /usr/sbin/policy-rc.d
        created_policy=0
    fi
    log "installed in $(since "$t0") s"
fi
for c in slurmctld slurmd sbatch squeue sinfo scontrol scancel munged munge unmunge; do
    command -v "$c" >/dev/null || die "$c is missing after the install"
done

# ---------------------------------------------------------------------------
# The cluster

WORK=$(mktemp -d "${PREFIX}XXXXXX")
chmod 755 "$WORK"
mkdir -p "$WORK/state" "$WORK/spool" "$WORK/log"
log "work folder $WORK"

# MUNGE: reuse a working munged; otherwise start one (and stop it at the end).
if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    log "munged is already running; using it"
else
    mkdir -p /run/munge
    chown munge:munge /run/munge
    chmod 755 /run/munge
    if [[ ! -s /etc/munge/munge.key ]]; then
        log "creating /etc/munge/munge.key"
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
        chown munge:munge /etc/munge/munge.key
        chmod 400 /etc/munge/munge.key
    fi
    rm -f /run/munge/munged.pid
    runuser -u munge -- /usr/sbin/munged 9>&- || die "munged did not start (see /var/log/munge/munged.log)"
    for ((i = 0; i < 50; i++)); do
        started_munged=$(daemon_pid /run/munge/munged.pid munged) && break
        sleep 0.1
    done
    [[ -n $started_munged ]] || die "munged wrote no pid file"
    echo "$started_munged" >"$WORK/munged.started"
    munge -n | unmunge >/dev/null || die "munged runs but does not decode its own credential"
    log "started munged (pid $started_munged)"
fi

# Two free ports for slurmctld and slurmd.
listening() { (: <"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
port=6817
while listening "$port" || listening "$((port + 1))"; do
    port=$((port + 2))
    ((port < 6917)) || die "no free port pair found in 6817-6916"
done

host=$(hostname -s)
# The node's real CPUs and memory, as slurmd measures them; a node configured
# with more than it has is drained.
node=$(slurmd -C | head -n 1)
[[ $node == NodeName=* ]] || die "slurmd -C printed no node line: $node"
node="NodeName=$host NodeAddr=127.0.0.1 ${node#NodeName=* }"

export SLURM_CONF=$WORK/slurm.conf
cat >"$SLURM_CONF" <<EOF
# One-node cluster for farm/slurm/test-local.sh (Slurm 22.05)
ClusterName=photonwave-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
MailProg=/bin/true
# No cgroups, no accounting
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
# A dependent job whose dependency can never be met is cancelled instead of
# pending forever (afterok on a failed task).
DependencyParameters=kill_invalid_depend
# Keep finished jobs for scontrol show job (there is no sacct without accounting).
MinJobAge=3600
KillWait=10
$node State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

t0=$EPOCHREALTIME
# 9>&-: the daemons must not inherit (and hold) the lock
slurmctld -f "$SLURM_CONF" 9>&- || die "slurmctld did not start (see $WORK/log/slurmctld.log)"
slurmd -f "$SLURM_CONF" 9>&- || die "slurmd did not start (see $WORK/log/slurmd.log)"
state=
for ((i = 0; i < 300; i++)); do
    state=$(sinfo -h -n "$host" -o %T 2>/dev/null || true)
    [[ $state == idle ]] && break
    sleep 0.1
done
if [[ $state != idle ]]; then
    tail -n 20 "$WORK/log/slurmctld.log" "$WORK/log/slurmd.log" >&2 || true
    die "node $host is '$state', not idle, 30 s after the daemons started"
fi
log "slurmctld and slurmd up, node $host idle after $(since "$t0") s (ports $port, $((port + 1)))"

# ---------------------------------------------------------------------------
# Helpers for the tests

# submit ARGS...: run submit.sh; sets render_job and merge_job.
submit() {
    local out
    echo "  \$ submit.sh $*"
    out=$("$SUBMIT" "$@" 2>"$WORK/submit.err") || {
        cat "$WORK/submit.err" >&2
        return 1
    }
    render_job=$(sed -n 's/^render_job=//p' <<<"$out")
    merge_job=$(sed -n 's/^merge_job=//p' <<<"$out")
    [[ -n $render_job ]]
}

# wait_jobs ID...: until no job of these (array) jobs is pending or running.
wait_jobs() {
    local deadline=$((SECONDS + TIMEOUT)) ids id queued
    ids=" $* "
    while ((SECONDS < deadline)); do
        queued=0
        while read -r id; do
            [[ $ids == *" $id "* ]] && queued=1
        done < <(squeue -h -o %F)
        ((queued)) || return 0
        sleep 0.3
    done
    echo "  jobs $* still queued after $TIMEOUT s:" >&2
    squeue >&2 || true
    return 1
}

# states ID: "STATE EXIT" per job (per array task, in task order).
states() {
    scontrol show job -o "$1" | sed -E 's/.*ArrayTaskId=([0-9]+).*JobState=([A-Z_]+).*ExitCode=([0-9:]+).*/\1 \2 \3/; t; s/.*JobState=([A-Z_]+).*ExitCode=([0-9:]+).*/- \1 \2/' | sort -n
}

# expect_states ID STATE...: the (array) job's tasks ended in these states, with exit 0:0 where COMPLETED.
expect_states() {
    local id=$1 got want
    shift
    want=$(printf '%s\n' "$@")
    got=$(states "$id" | awk '{print $2}')
    if [[ $got == "$want" ]]; then
        ok "job $id: $(echo "$got" | tr '\n' ' ')"
        if states "$id" | awk '$2 == "COMPLETED" && $3 != "0:0" {bad=1} END {exit bad}'; then :; else
            bad "job $id: a completed task has a non-zero exit code: $(states "$id" | tr '\n' ';')"
        fi
    else
        bad "job $id ended as $(echo "$got" | tr '\n' ' '), wanted $*"
        show_logs "$id"
    fi
}

show_logs() {
    echo "  --- scontrol show job $1:" >&2
    scontrol show job "$1" >&2 || true
}

# dump_logs DIR: the job logs of a test, on failure.
dump_logs() {
    local f
    for f in "$1"/logs/*.out; do
        [[ -f $f ]] || continue
        echo "  --- $f:" >&2
        tail -n 15 "$f" >&2
    done
}

# local_render PASSES OUT: the undivided render to compare with.
local_render() {
    log "local render: photonwave render $(basename "$SCENE") --passes $1 ${FLAGS[*]}"
    "$PHOTONWAVE" render "$SCENE" --passes "$1" "${FLAGS[@]}" -o "$2" -q
}

name=$(basename "$SCENE")
name=${name%.*}

# ---------------------------------------------------------------------------
# Tests

# Submits through submit.sh (its arguments) and waits for the render and merge jobs; fails the
# test when the submission fails.
submit_and_wait() {
    submit "$@" || {
        bad "submit.sh failed"
        return 1
    }
    echo "  render job $render_job, merge job $merge_job"
    wait_jobs "$render_job" "$merge_job" || bad "jobs did not finish in time"
}

test_split() {
    local out=$WORK/split passes=7 tasks=3 k
    log "test split: $tasks tasks, $passes passes"
    submit_and_wait "$SCENE" "$out" "$tasks" "$passes" -- "${FLAGS[@]}" || return
    expect_states "$render_job" COMPLETED COMPLETED COMPLETED
    expect_states "$merge_job" COMPLETED
    for ((k = 0; k < tasks; k++)); do
        check "part-$k.exr written" test -s "$out/parts/part-$k.exr"
        check "checkpoint of task $k removed" test ! -e "$out/checkpoints/part-$k.exr"
    done
    check "$name.exr, .png and .json written" test -s "$out/$name.exr" -a -s "$out/$name.png" -a -s "$out/$name.json"
    local_render "$passes" "$WORK/local-$passes.exr"
    check "merged image equals 'render --passes $passes' bit for bit (cmp)" cmp "$out/$name.exr" "$WORK/local-$passes.exr"
    ((failed == 0)) || dump_logs "$out"
}

test_failure() {
    local out=$WORK/failure wrapper=$WORK/failing-photonwave reason
    log "test failure: task 1 of 3 fails"
    cat >"$wrapper" <<EOF
#!/bin/sh
# photonwave, except that array task 1 fails at once
if [ "\${SLURM_ARRAY_TASK_ID:-}" = 1 ] && [ "\$1" = render ]; then
    echo "simulated failure of task 1" >&2
    exit 3
fi
exec "$PHOTONWAVE" "\$@"
EOF
    chmod 755 "$wrapper"
    submit --photonwave "$wrapper" "$SCENE" "$out" 3 3 -- "${FLAGS[@]}" || {
        bad "submit.sh failed"
        return
    }
    echo "  render job $render_job, merge job $merge_job"
    wait_jobs "$render_job" "$merge_job" || bad "the merge job still waits after a failed task"
    expect_states "$render_job" COMPLETED FAILED COMPLETED
    expect_states "$merge_job" CANCELLED
    reason=$(scontrol show job -o "$merge_job" | grep -o 'Reason=[^ ]*' || true)
    echo "  merge job: $reason"
    check "no merged image after a failed task" test ! -e "$out/$name.exr"
}

test_interrupt() {
    local out=$WORK/interrupt passes=${INTERRUPT_PASSES:-300} tasks=2 i st before
    log "test interrupt: $tasks tasks, $passes passes; task 0 gets SIGTERM while it renders"
    submit --checkpoint-every 1s "$SCENE" "$out" "$tasks" "$passes" -- "${FLAGS[@]}" || {
        bad "submit.sh failed"
        return
    }
    echo "  render job $render_job, merge job $merge_job"
    # Wait until task 0 has saved a checkpoint: it is rendering.
    for ((i = 0; i < 600; i++)); do
        [[ -s $out/checkpoints/part-0.exr ]] && break
        sleep 0.1
    done
    st=$(squeue -h -j "${render_job}_0" -o %T 2>/dev/null || true)
    if [[ $st != RUNNING ]]; then
        bad "task 0 is '$st', not RUNNING, when it should be interrupted (raise INTERRUPT_PASSES)"
        wait_jobs "$render_job" "$merge_job" || true
        return
    fi
    echo "  scancel --batch --signal=TERM ${render_job}_0 (as Slurm does before the time limit)"
    scancel --batch --signal=TERM "${render_job}_0"
    wait_jobs "$render_job" "$merge_job" || bad "jobs did not finish in time"
    expect_states "$render_job" COMPLETED COMPLETED
    expect_states "$merge_job" COMPLETED
    check "task 0 says it stopped early" grep -q 'stopped early by a signal' "$out/logs/render-${render_job}_0.out"
    check "task 0 kept its checkpoint" test -s "$out/checkpoints/part-0.exr"
    local_render "$passes" "$WORK/local-$passes.exr"
    if [[ -s $out/$name.exr ]] && ! cmp -s "$out/$name.exr" "$WORK/local-$passes.exr"; then
        ok "the merge of the interrupted run lacks passes (differs from the full render)"
    else
        bad "the merge of the interrupted run is missing or already complete"
    fi
    if grep -qi 'missing\|lack' "$out"/logs/merge-"$merge_job".out; then
        ok "the merge warned about missing passes"
    else
        bad "the merge did not warn about missing passes"
    fi
    before=$merge_job
    echo "  resubmitting task 0: it continues from its checkpoint"
    submit --array 0 --checkpoint-every 1s "$SCENE" "$out" "$tasks" "$passes" -- "${FLAGS[@]}" || {
        bad "submit.sh --array 0 failed"
        return
    }
    echo "  render job $render_job, merge job $merge_job"
    wait_jobs "$render_job" "$merge_job" || bad "jobs did not finish in time"
    expect_states "$render_job" COMPLETED
    expect_states "$merge_job" COMPLETED
    check "the resubmitted task resumed" grep -q -- '--resume' "$out/logs/render-${render_job}_0.out"
    check "checkpoint of task 0 removed" test ! -e "$out/checkpoints/part-0.exr"
    check "merged image equals 'render --passes $passes' bit for bit (cmp)" cmp "$out/$name.exr" "$WORK/local-$passes.exr"
    [[ $before != "$merge_job" ]] || bad "no new merge job"
    ((failed == 0)) || dump_logs "$out"
}

test_budget() {
    local out=$WORK/budget
    log "test budget: 3 tasks with --time 2s each"
    submit_and_wait --time 2s "$SCENE" "$out" 3 -- "${FLAGS[@]}" || return
    expect_states "$render_job" COMPLETED COMPLETED COMPLETED
    expect_states "$merge_job" COMPLETED
    check "$name.exr written" test -s "$out/$name.exr"
    ((failed == 0)) || dump_logs "$out"
}

test_walltime() {
    local out=$WORK/walltime k
    log "test walltime: 2 tasks with --time 10m under a 2-minute Slurm time limit"
    submit_and_wait --time 10m --wall 2 "$SCENE" "$out" 2 -- "${FLAGS[@]}" || return
    expect_states "$render_job" COMPLETED COMPLETED
    expect_states "$merge_job" COMPLETED
    for ((k = 0; k < 2; k++)); do
        check "task $k was stopped by Slurm's SIGTERM" grep -q 'stopped early by a signal' "$out/logs/render-${render_job}_$k.out"
    done
    check "$name.exr written" test -s "$out/$name.exr"
    ((failed == 0)) || dump_logs "$out"
}

for t in $TESTS; do
    case $t in
        split | failure | interrupt | budget | walltime) "test_$t" ;;
        *) die "unknown test '$t' (split failure interrupt budget walltime)" ;;
    esac
done

log "done"
echo "test-local: $passed passed, $failed failed"
if ((failed == 0)); then
    echo "PASS"
else
    echo "FAIL"
    exit 1
fi
