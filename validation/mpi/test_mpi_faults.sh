#!/usr/bin/env bash
# Faults of the MPI job as a cluster deals them: a worker killed mid-task
# (SIGKILL, SIGTERM), a worker or rank 0 that stops answering (SIGSTOP), a
# rank whose MPI transport cannot start, a worker out of memory, a full disk
# under rank 0's output. Each must end the job within
# seconds, with a non-zero status, a message naming the task or the rank,
# and no output or temporary file left behind.
# Usage: test_mpi_faults.sh tetiso mpiexec [sanitized]
# ("sanitized": AddressSanitizer reserves terabytes of address space, so the
# cases that limit it with ulimit -v cannot run there.)
set -u
tetiso=$1
mpiexec=${2:-mpirun}
sanitized=${3:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
passed=0
failures=0

# on_rank.sh R SETUP COMMAND...: COMMAND on every rank, after SETUP (shell
# code: a ulimit, or writing the pid) on rank R alone.
cat >"$work/on_rank.sh" <<'EOF'
#!/usr/bin/env bash
rank=$1 setup=$2
shift 2
[ "${OMPI_COMM_WORLD_RANK:-0}" = "$rank" ] && eval "$setup"
exec "$@"
EOF
chmod +x "$work/on_rank.sh"

# check WHAT STATUS SECONDS MOST PATTERN: the job's outcome against the rules.
check() {
    local what=$1 status=$2 elapsed=$3 most=$4 pattern=$5 problem=""
    [ "$status" -ne 0 ] || problem="exit status 0"
    [ "$status" -ne 124 ] || problem="hung until the test's timeout"
    [ "$elapsed" -le "$most" ] || problem="${problem:+$problem; }took ${elapsed} s, more than $most"
    grep -qE "$pattern" "$work/stderr" || problem="${problem:+$problem; }no line matches '$pattern'"
    [ -z "$(ls -A "$work/out")" ] || problem="${problem:+$problem; }left behind: $(ls -A "$work/out")"
    if [ -n "$problem" ]; then
        echo "FAIL: $what: $problem"
        sed 's/^/  | /' "$work/stderr" | head -20
        failures=$((failures + 1))
    else
        passed=$((passed + 1))
    fi
}

# fault WHAT MOST PATTERN RANK SETUP ARGS...: the job run with SETUP on RANK.
fault() {
    local what=$1 most=$2 pattern=$3 rank=$4 setup=$5
    shift 5
    rm -rf "$work/out" && mkdir "$work/out"
    local start
    start=$(date +%s)
    timeout 120 "$mpiexec" --oversubscribe -np 3 "$work/on_rank.sh" "$rank" "$setup" "$tetiso" "$@" \
        >"$work/stdout" 2>"$work/stderr"
    local status=$?
    check "$what" "$status" $(($(date +%s) - start)) "$most" "$pattern"
}

# A worker killed while it holds a task: the launcher names the rank and the
# signal, rank 0 the task each rank held. The job is long enough (tens of
# seconds alone) that the kill lands in the domain phase.
for signal in KILL TERM; do
    rm -rf "$work/out" && mkdir "$work/out" && rm -f "$work/rank1.pid"
    start=$(date +%s)
    timeout 120 "$mpiexec" --oversubscribe -np 3 "$work/on_rank.sh" 1 "echo \$\$ >$work/rank1.pid" \
        "$tetiso" run --lattice 120 --domains 27 --quiet -o "$work/out/s.ply" --report "$work/out/r.json" \
        >"$work/stdout" 2>"$work/stderr" &
    job=$!
    for _ in $(seq 100); do [ -s "$work/rank1.pid" ] && break; sleep 0.1; done
    sleep 2 # start-up, then into the domain tasks
    kill -s "$signal" "$(cat "$work/rank1.pid")"
    wait "$job"
    status=$?
    check "worker killed by SIG$signal" "$status" $(($(date +%s) - start)) 60 "rank 1 held task '"
done

# A rank that stops answering (SIGSTOP: a hung node looks the same): a
# worker past its task's deadline is named by rank 0, a silent rank 0 by a
# worker, and the job is aborted with status 2 before anything is written.
# With --task-timeout 2 a task's deadline is 2 s or ten times its predicted
# time (domains take about a second here), a silent rank 0's about 2 s.
for rank in 1 0; do
    rm -rf "$work/out" && mkdir "$work/out" && rm -f "$work/rank$rank.pid"
    start=$(date +%s)
    timeout 120 "$mpiexec" --oversubscribe -np 3 "$work/on_rank.sh" "$rank" "echo \$\$ >$work/rank$rank.pid" \
        "$tetiso" run --lattice 120 --domains 27 --task-timeout 2 --quiet -o "$work/out/s.ply" \
        --report "$work/out/r.json" >"$work/stdout" 2>"$work/stderr" &
    job=$!
    for _ in $(seq 100); do [ -s "$work/rank$rank.pid" ] && break; sleep 0.1; done
    sleep 3 # start-up, then into the domain tasks
    pid=$(cat "$work/rank$rank.pid")
    kill -s STOP "$pid"
    wait "$job"
    status=$?
    kill -s CONT "$pid" 2>/dev/null
    if [ "$rank" = 1 ]; then
        pattern="rank 1 stopped answering: its task '[^']+' did not end within [0-9]+ s"
    else
        pattern="rank 0 sent nothing for [0-9]+ s"
    fi
    check "rank $rank stopped" "$status" $(($(date +%s) - start)) 40 "$pattern"
    [ "$status" -eq 2 ] || { echo "FAIL: rank $rank stopped: exit status $status, not 2"; failures=$((failures + 1)); }
done

# The deadline's floor is a number of seconds >= 0: anything else is refused
# before any rank starts, in one line, with status 2.
for bad in -1 nan inf abc; do
    rm -rf "$work/out" && mkdir "$work/out"
    "$tetiso" run --lattice 10 --task-timeout "$bad" -o "$work/out/s.ply" >"$work/stdout" 2>"$work/stderr"
    status=$?
    if [ "$status" -ne 2 ] || [ "$(wc -l <"$work/stderr")" -ne 1 ] || ! grep -q -- "--task-timeout" "$work/stderr" ||
        [ -n "$(ls -A "$work/out")" ]; then
        echo "FAIL: --task-timeout $bad: status $status: $(head -2 "$work/stderr")"
        failures=$((failures + 1))
    else
        passed=$((passed + 1))
    fi
done

# Rank 0's disk full under the output (a file-size limit): the write fails,
# the job ends non-zero naming the output, and neither it nor the report
# (nor a temporary of either) is left.
fault "full disk on rank 0" 60 "out/s.ply: cannot write: File too large" 0 "ulimit -f 64" \
    run --lattice 60 --domains 8 --quiet -o "$work/out/s.ply" --report "$work/out/r.json"

if [ -z "$sanitized" ]; then
    # A rank that cannot start: its shared-memory transport cannot map its
    # segment; the others used to wait for it in the first collective until
    # killed. Where the limit bites depends on how much address space the
    # binary and Open MPI's components take before it, which changes with
    # every library and build: MPI_Init returns and the start-up check names
    # the unreachable ranks; or rank 1 gets through and its first task runs
    # out of memory, named with the task and the rank; or Open MPI faults
    # inside MPI_Init, before tetiso runs, and mpirun names the rank and the
    # signal; or Open MPI cannot load its point-to-point transport there and
    # names the process (host and pid) it could not start. A limit derived
    # from the binary's mappings would only pick one of these by a margin
    # that the next library moves, so all four are accepted: the promise is
    # that the job ends, the rank is named, and nothing is left behind.
    fault "a rank that cannot start" 40 "could not all reach each other|task 'domain [0-9]+' failed on rank 1: out of memory|process rank 1 with PID [0-9]+ on node [^ ]+ exited on signal [0-9]+|\\[[^]:]+:[0-9]+\\] PML [a-z0-9]+ cannot be selected" 1 "ulimit -v 60000" \
        run --lattice 20 --domains 8 --quiet -o "$work/out/s.ply"
    # A worker out of memory in its task: reported by the worker, named by
    # rank 0 with the task.
    fault "worker out of memory" 60 "task 'domain [0-9]+' failed on rank 1: out of memory" 1 "ulimit -v 400000" \
        run --lattice 160 --domains 2 --quiet -o "$work/out/s.ply"
fi

echo "$passed passed, $failures failed"
[ "$failures" -eq 0 ]
