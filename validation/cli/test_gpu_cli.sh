#!/usr/bin/env bash
# The command line's GPU paths: `--device gpu` writes the bytes `--device cpu`
# writes (compared with cmp), for run (alone and under mpirun), extract
# --reduce and reduce, and its reports name the device. Where there is no GPU
# (CI), asking for one must be a one-line error and exit status 2 with
# nothing written. Usage: test_gpu_cli.sh PATH/TO/tetiso [mpiexec]
set -u
tetiso=$1
mpiexec=${2:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0

fail() {
    echo "FAIL: $*"
    failures=$((failures + 1))
}

# same WHAT ARGS...: the command with --device cpu and with --device gpu
# writes identical surfaces.
same() {
    local what=$1
    shift
    "$tetiso" "$@" --device cpu -o "$work/cpu.ply" --report "$work/cpu.json" 2>"$work/err" || {
        fail "$what (cpu): $(cat "$work/err")"
        return
    }
    "$tetiso" "$@" --device gpu -o "$work/gpu.ply" --report "$work/gpu.json" 2>"$work/err" || {
        fail "$what (gpu): $(cat "$work/err")"
        return
    }
    cmp -s "$work/cpu.ply" "$work/gpu.ply" || fail "$what: the GPU's surface differs from the CPU's"
    grep -q '"gpu' "$work/gpu.json" || fail "$what: the report does not name the GPU"
}

if ! "$tetiso" extract --lattice 8 --device gpu -o "$work/probe.ply" 2>"$work/err"; then
    # No GPU here: a clear refusal from every command that takes --device.
    "$tetiso" extract --lattice 8 --field sphere -o "$work/in.ply" || fail "extract on the CPU"
    for args in "extract --lattice 8 --reduce" "run --lattice 10 --domains 2" "reduce $work/in.ply"; do
        rm -f "$work/out.ply"
        # shellcheck disable=SC2086
        "$tetiso" $args --device gpu -o "$work/out.ply" 2>"$work/err"
        status=$?
        [ "$status" -eq 2 ] || fail "$args --device gpu: exit status $status, expected 2"
        [ "$(wc -l <"$work/err")" -eq 1 ] || fail "$args --device gpu: stderr is not one line: $(cat "$work/err")"
        grep -q -- "--device gpu: " "$work/err" || fail "$args --device gpu: the message does not say why: $(cat "$work/err")"
        [ ! -e "$work/out.ply" ] || fail "$args --device gpu: left an output"
    done
    [ "$failures" -eq 0 ] && echo "no GPU: every --device gpu is a clear error" && exit 0
    exit 1
fi

same "run, lattice" run --lattice 60 --domains 8 --quiet
grep -q '"device": "gpu 0"' "$work/gpu.json" || fail "run: no task ran on gpu 0"
same "run, gyroid in 27 domains" run --lattice 48 --domains 27 --field gyroid --quiet
same "run, unstructured mesh" run --mesh "$(dirname "$0")/../../meshes/cube.1" --domains 4 --field sphere --level 1.5 --quiet
same "extract --reduce" extract --lattice 60 --domains 4 --reduce
"$tetiso" extract --lattice 50 --field torus -o "$work/raw.ply" || fail "extract"
same "reduce" reduce "$work/raw.ply"
# The GPUs this machine shows CUDA.
if [ -n "${CUDA_VISIBLE_DEVICES:-}" ]; then
    gpus=$(echo "$CUDA_VISIBLE_DEVICES" | tr ',' '\n' | grep -c .)
else
    gpus=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU')
fi
[ "$gpus" -ge 1 ] || gpus=1
# drivers REPORT DEVICE RANKS [every]: the tasks on each GPU ran on one rank,
# its driver: rank 1 + k drives GPU k where there are two workers or more (the
# node's lowest workers drive its GPUs, one each, a worker left for the
# seams), the lone worker runs them all where there is one. Some task ran on
# a GPU; under --device gpu every domain task did; with `every`, each GPU that
# has a driver got tasks. The seams rank 0 runs itself, the root always among
# them, reduce on a GPU of its node, and no other seam on any.
drivers() {
    /usr/bin/python3 - "$@" "$gpus" <<'PY' || fail "mpirun -np $3 --device $2: $(cat "$1.why")"
import json, sys
report, device, ranks = json.load(open(sys.argv[1])), sys.argv[2], int(sys.argv[3])
every, gpus = sys.argv[4] == "every", int(sys.argv[-1])
workers = ranks - 1
driven = min(gpus, workers - 1) if workers >= 2 else 0
ranks_of = {}
seams_here = 0
why = None
for t in report["tasks"]:
    if t["kind"] == "seam":
        seams_here += t["device"] != "cpu" and t["rank"] == 0
    if t["device"] != "cpu" and t["rank"] != 0:
        ranks_of.setdefault(int(t["device"].split()[1]), set()).add(t["rank"])
if ranks > 1 and seams_here == 0:
    why = "rank 0 reduced no seam on a GPU"
if not ranks_of:
    why = "no task ran on a GPU"
for gpu, on in sorted(ranks_of.items()):
    expected = 1 + gpu if driven else 1
    if on != {expected} or (driven and gpu >= driven):
        why = "the tasks of GPU %d ran on ranks %s, not on its driver, rank %d" % (gpu, sorted(on), expected)
if device == "gpu" and any(t["kind"] == "domain" and t["device"] == "cpu" for t in report["tasks"]):
    why = "a domain task ran on the CPU under --device gpu"
if every and sorted(ranks_of) != list(range(max(driven, 1))):
    why = "tasks ran on GPUs %s of the %d driven" % (sorted(ranks_of), max(driven, 1))
open(sys.argv[1] + ".why", "w").write(why or "")
sys.exit(1 if why else 0)
PY
}

if [ -n "$mpiexec" ]; then
    # Two ranks (a lone worker, which runs every GPU's tasks itself), three
    # (the lowest worker drives GPU 0, the other runs the seams) and five
    # (the lowest workers drive up to two GPUs, every GPU fed with batches),
    # against one process on the CPU.
    "$tetiso" run --lattice 60 --domains 8 --quiet --device cpu -o "$work/alone.ply" || fail "run alone"
    "$tetiso" run --lattice 80 --domains 64 --quiet --device cpu -o "$work/alone64.ply" || fail "run alone"
    mpi() { # RANKS DOMAINS DEVICE ARGS...: the job under mpirun, against one CPU process
        local ranks=$1 domains=$2 device=$3 lattice=60 alone=$work/alone.ply
        shift 3
        [ "$domains" -eq 64 ] && lattice=80 alone=$work/alone64.ply
        OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "$mpiexec" --oversubscribe -np "$ranks" \
            "$tetiso" run --lattice $lattice --domains "$domains" --quiet --device "$device" "$@" -o "$work/ranks.ply" \
            --report "$work/ranks.json" 2>"$work/err" || {
            fail "run under mpirun -np $ranks --device $device $*: $(cat "$work/err")"
            return 1
        }
        cmp -s "$alone" "$work/ranks.ply" ||
            fail "run under mpirun -np $ranks --device $device $* differs from one CPU process"
    }
    for ranks in 2 3 5; do
        for device in gpu auto; do
            mpi $ranks 8 $device && drivers "$work/ranks.json" $device $ranks
        done
    done
    # Many domains, small batches: every driven GPU gets some, under gpu and auto.
    for device in gpu auto; do
        mpi 5 64 $device --gpu-batch 4 && drivers "$work/ranks.json" $device 5 every
    done
    # --gpu names one GPU: only it is used, by one driver.
    if [ "$gpus" -ge 2 ]; then
        mpi 5 8 gpu --gpu 1 && /usr/bin/python3 - "$work/ranks.json" <<'PY' || fail "--gpu 1: $(cat "$work/why")"
import json, os, sys
report = json.load(open(sys.argv[1]))
on = {(t["device"], t["rank"]) for t in report["tasks"] if t["device"] != "cpu" and t["kind"] == "domain"}
seams = {t["device"] for t in report["tasks"] if t["device"] != "cpu" and t["kind"] == "seam"}
why = "" if on == {("gpu 1", 1)} else "GPU tasks ran as %s, not on gpu 1 by rank 1" % sorted(on)
if seams - {"gpu 1"}:
    why = "seams reduced on %s, not on gpu 1" % sorted(seams)
open(os.path.join(os.path.dirname(sys.argv[1]), "why"), "w").write(why)
sys.exit(1 if why else 0)
PY
    fi
fi
# The resource manager's choice, task by task: the surface whatever it is,
# and with a GPU at hand some domain tasks on it.
"$tetiso" run --lattice 60 --domains 27 --quiet --device cpu -o "$work/cpu.ply" || fail "run on the CPU"
"$tetiso" run --lattice 60 --domains 27 --quiet --device auto -o "$work/auto.ply" --report "$work/auto.json" \
    2>"$work/err" || fail "run --device auto: $(cat "$work/err")"
cmp -s "$work/cpu.ply" "$work/auto.ply" || fail "run --device auto differs from --device cpu"
grep -q '"device": "gpu 0"' "$work/auto.json" || fail "run --device auto: no task ran on the GPU"
# One process, --device gpu: every GPU of the machine takes grants in turn.
if [ "$gpus" -ge 2 ]; then
    "$tetiso" run --lattice 60 --domains 27 --quiet --device gpu --gpu-batch 2 -o "$work/gpus.ply" \
        --report "$work/gpus.json" 2>"$work/err" || fail "run --device gpu on $gpus GPUs: $(cat "$work/err")"
    cmp -s "$work/cpu.ply" "$work/gpus.ply" || fail "run --device gpu on $gpus GPUs differs from --device cpu"
    grep -q '"device": "gpu 1"' "$work/gpus.json" || fail "run --device gpu: no task ran on GPU 1"
fi
[ "$failures" -eq 0 ] && echo "the GPU wrote the CPU's bytes everywhere" && exit 0
exit 1
