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
# one_driver REPORT DEVICE RANKS: every task on the GPU ran on one rank (the
# GPU's driver: rank 1, the node's lowest worker, where there are two workers
# or more), some did, and under --device gpu every domain task did.
one_driver() {
    /usr/bin/python3 - "$@" <<'PY' || fail "mpirun -np $3 --device $2: $(cat "$1.why")"
import json, sys
report, device, ranks = json.load(open(sys.argv[1])), sys.argv[2], int(sys.argv[3])
on_gpu = [t for t in report["tasks"] if t["device"] != "cpu"]
why = None
if not on_gpu:
    why = "no task ran on the GPU"
elif len({t["rank"] for t in on_gpu}) != 1 or (ranks > 2 and on_gpu[0]["rank"] != 1):
    why = "GPU tasks ran on ranks %s, not on one driver" % sorted({t["rank"] for t in on_gpu})
elif device == "gpu" and any(t["kind"] == "domain" and t["device"] == "cpu" for t in report["tasks"]):
    why = "a domain task ran on the CPU under --device gpu"
open(sys.argv[1] + ".why", "w").write(why or "")
sys.exit(1 if why else 0)
PY
}

if [ -n "$mpiexec" ]; then
    # Two ranks (a lone worker, which runs the GPU's tasks itself), three
    # and five (the lowest worker drives the GPU, the others run the CPU's
    # tasks), against one process on the CPU.
    "$tetiso" run --lattice 60 --domains 8 --quiet --device cpu -o "$work/alone.ply" || fail "run alone"
    for ranks in 2 3 5; do
        for device in gpu auto; do
            OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "$mpiexec" --oversubscribe -np $ranks \
                "$tetiso" run --lattice 60 --domains 8 --quiet --device $device -o "$work/ranks.ply" \
                --report "$work/ranks.json" 2>"$work/err" || {
                fail "run under mpirun -np $ranks --device $device: $(cat "$work/err")"
                continue
            }
            cmp -s "$work/alone.ply" "$work/ranks.ply" ||
                fail "run under mpirun -np $ranks --device $device differs from one CPU process"
            one_driver "$work/ranks.json" $device $ranks
        done
    done
fi
# The resource manager's choice, task by task: the surface whatever it is,
# and with a GPU at hand some domain tasks on it.
"$tetiso" run --lattice 60 --domains 27 --quiet --device cpu -o "$work/cpu.ply" || fail "run on the CPU"
"$tetiso" run --lattice 60 --domains 27 --quiet --device auto -o "$work/auto.ply" --report "$work/auto.json" \
    2>"$work/err" || fail "run --device auto: $(cat "$work/err")"
cmp -s "$work/cpu.ply" "$work/auto.ply" || fail "run --device auto differs from --device cpu"
grep -q '"device": "gpu 0"' "$work/auto.json" || fail "run --device auto: no task ran on the GPU"
[ "$failures" -eq 0 ] && echo "the GPU wrote the CPU's bytes everywhere" && exit 0
exit 1
