#!/usr/bin/python3
"""The soundness soak, the geometric counterpart of the fuzzers: random jobs,
each surface checked against the contract (docs/ARCHITECTURE.md,
"Contracts") with `tetiso check --strict`.

    tools/soak.py [--tetiso BIN] [--jobs N] [--seed S] [--minutes M]
                  [--max-lattice N] [--mpirun MPIRUN] [--gpu] [--json FILE] [--keep DIR]

Job i of seed S is drawn from random.Random(f"{S}:{i}") alone, so any job is
reproduced by its seed and index, and each record names its commands too.
A job draws:
  - a mesh: the lattice (N nodes per axis) or a mesh of meshes/ (TetGen's
    cube.1, a Gmsh or VTK file of meshes/solver/), split by recursive
    bisection or METIS into 1 to 16 domains;
  - a field: a built-in (paper, sphere, torus, gyroid) or an expression from
    a small grammar (spheres, tori, waves, planes, quadrics, their products,
    sums, minima and maxima: creases);
  - a level: exactly the float value of one of the mesh's nodes (often one on
    a bisection plane), a few ulps beside it, or anywhere in the field's range;
  - a command: `extract` (raw or --reduce), `run` (threads, --seam-rings,
    --sample-rings, --max-error, --phi, --no-reduce), under mpirun with 2 or
    3 ranks where MPIRUN is given, on the GPU with --gpu.
Each final surface must pass `tetiso check --strict`; a reduced one must also
keep the raw surface's component signatures (`check --strict RAW --against
OUT`) and, on the lattice, every raw vertex within --max-error of it. A
failure is recorded with the commands that reproduce it. Exit status: 0 when
every job passed, 1 otherwise.
"""
import argparse
import json
import math
import os
import platform
import random
import shlex
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MESHES = ["meshes/cube.1", "meshes/solver/cube-4.1.msh", "meshes/solver/cube-binary-zlib.vtu"]
BUILTINS = ["paper", "sphere", "torus", "gyroid"]


def to_float32(value):
    return struct.unpack("f", struct.pack("f", value))[0]


def ulps_from(value, k):
    """The float k ulps above (k > 0) or below a float value, across zero too:
    floats in order are the integers of their bits, negatives mirrored."""
    bits = struct.unpack("I", struct.pack("f", value))[0]
    order = -(bits & 0x7fffffff) if bits & 0x80000000 else bits
    order += k
    bits = order if order >= 0 else (-order) | 0x80000000
    return struct.unpack("f", struct.pack("I", bits))[0]


# ----------------------------------------------------------------- the fields
# An expression is a pair (muparser text, Python text): the numbers are
# written with a few digits, so both parse them to the same doubles.

def number(rng, lo, hi, digits=3):
    return f"{round(rng.uniform(lo, hi), digits):g}"


def shape(rng, depth=0):
    kind = rng.choice(["sphere", "torus", "wave", "plane", "quadric", "waves"] +
                      (["min", "max", "sum", "product"] if depth < 2 else []))
    if kind == "sphere":
        a, b, c = (number(rng, 1.0, 4.0) for _ in range(3))
        return f"sqrt((x-{a})^2+(y-{b})^2+(z-{c})^2)"
    if kind == "torus":
        a, b, c, r = number(rng, 2.0, 3.0), number(rng, 2.0, 3.0), number(rng, 2.0, 3.0), number(rng, 0.8, 1.6)
        return f"sqrt((sqrt((x-{a})^2+(y-{b})^2)-{r})^2+(z-{c})^2)"
    if kind == "wave":
        return (f"{number(rng, 0.3, 1.0)}*cos({number(rng, -3, 3)}*x+{number(rng, -3, 3)}*y+"
                f"{number(rng, -3, 3)}*z+{number(rng, 0, 6.3)})")
    if kind == "waves":
        return (f"sin({number(rng, 1, 4)}*x)*cos({number(rng, 1, 4)}*y)+sin({number(rng, 1, 4)}*y)*"
                f"cos({number(rng, 1, 4)}*z)+sin({number(rng, 1, 4)}*z)*cos({number(rng, 1, 4)}*x)")
    if kind == "plane":
        return f"{number(rng, -1, 1)}*x+{number(rng, -1, 1)}*y+{number(rng, -1, 1)}*z"
    if kind == "quadric":
        return (f"{number(rng, -1, 1)}*(x-2.5)^2+{number(rng, -1, 1)}*(y-2.5)^2+{number(rng, -1, 1)}*(z-2.5)^2+"
                f"{number(rng, -1, 1)}*(x-2.5)*(y-2.5)")
    a, b = shape(rng, depth + 1), shape(rng, depth + 1)
    if kind in ("min", "max"):
        return f"{kind}({a},{b})"
    return f"({a}){'+' if kind == 'sum' else '*'}({b})"


def python_of(expression):
    return (expression.replace("^", "**").replace("sqrt", "math.sqrt").replace("sin", "math.sin")
            .replace("cos", "math.cos"))


def builtin_value(name, x, y, z):
    """field_formulas.hpp's formulas (its own sin and cos round alike to a
    float, or an ulp off: the level is near the node either way)."""
    if name == "paper":
        return 2 * math.cos(10 * x) + 2 * math.sin(10 * y) + math.cos(10 * z)
    if name == "sphere":
        return math.sqrt((x - 2.5) ** 2 + (y - 2.5) ** 2 + (z - 2.5) ** 2)
    if name == "torus":
        return math.hypot(math.hypot(x - 2.5, y - 2.5) - 1.5, z - 2.5)
    k = 2 * math.pi / 2.5
    return (math.sin(k * x) * math.cos(k * y) + math.sin(k * y) * math.cos(k * z) +
            math.sin(k * z) * math.cos(k * x))


def field_function(field):
    if field in BUILTINS:
        return lambda x, y, z: builtin_value(field, x, y, z)
    code = compile(python_of(field), "<field>", "eval")
    return lambda x, y, z: eval(code, {"math": math, "min": min, "max": max, "x": x, "y": y, "z": z})


# ------------------------------------------------------------------ the nodes

def tetgen_nodes(base):
    lines = [line.split() for line in Path(f"{base}.node").read_text().splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    return [tuple(float(v) for v in line[1:4]) for line in lines[1:]]


def solver_nodes():
    """The nodes of meshes/solver/ (one mesh in every encoding), from its ASCII file."""
    text = (ROOT / "meshes/solver/cube-ascii.vtu").read_text()
    start = text.index('Name="Points"')
    values = [float(v) for v in text[text.index(">", start) + 1:text.index("</DataArray>", start)].split()]
    return [tuple(values[i:i + 3]) for i in range(0, len(values), 3)]


MESH_NODES = {}


def mesh_nodes(mesh):
    """Node coordinates of a mesh of meshes/, for levels at node values."""
    if mesh not in MESH_NODES:
        MESH_NODES[mesh] = tetgen_nodes(ROOT / mesh) if mesh.endswith(".1") else solver_nodes()
    return MESH_NODES[mesh]


def lattice_node(rng, n):
    """A lattice node, half the time on a middle plane (where bisection cuts)."""
    index = [rng.randrange(n) for _ in range(3)]
    if rng.random() < 0.5:
        index[rng.randrange(3)] = rng.choice([(n - 1) // 2, n // 2, (n - 1) // 4, 3 * (n - 1) // 4])
    return tuple(5.0 * i / (n - 1) for i in index)


# ------------------------------------------------------------------- the jobs

def draw_job(seed, index, args):
    rng = random.Random(f"{seed}:{index}")
    job = {"index": index}
    on_mesh = rng.random() < 0.15
    if on_mesh:
        job["mesh"] = rng.choice(MESHES)
        source = ["--mesh", str(ROOT / job["mesh"])]
        nodes = mesh_nodes(job["mesh"])
        domains = rng.choice([1, 2, 3, 5, 8])
    else:
        job["lattice"] = n = rng.randint(5, args.max_lattice)
        source = ["--lattice", str(n)]
        domains = min(rng.choice([1, 2, 3, 4, 5, 7, 8, 12, 16]), (n - 1) ** 3)
    field = rng.choice(BUILTINS) if rng.random() < 0.3 else shape(rng)
    if on_mesh and job["mesh"].endswith((".msh", ".vtu")) and rng.random() < 0.3:
        field = None  # the file's own point array
    value = field_function(field) if field else None

    # The level: a node's float value, a few ulps beside it, or anywhere.
    how = rng.choice(["node", "node", "ulps", "range"]) if value else "array"
    if how == "array":
        level = number(rng, 0.5, 2.5)
    else:
        points = [rng.choice(nodes) if on_mesh else lattice_node(rng, n) for _ in range(12)]
        values = sorted(v for v in (to_float32(value(*p)) for p in points) if math.isfinite(v))
        if len(values) < 3:  # a field undefined at most nodes (a root of a negative): any level
            how, values = "range", [-1.0, -1.0, 1.0, 1.0]
        if how == "range":
            level = repr(to_float32(rng.uniform(values[1], values[-2])))
        else:
            at = values[rng.randrange(len(values))]
            level = repr(at if how == "node" else ulps_from(at, rng.choice([-8, -3, -2, -1, 1, 2, 3, 8])))
    job["level_kind"] = how
    common = source + (["--field", field] if field else ["--array", "distance"]) + ["--level", level]

    threads = ["--threads", str(rng.choice([1, 1, 2]))]
    kind = rng.choice(["extract", "extract --reduce", "run", "run", "run", "run --no-reduce"])
    if args.mpirun and kind.startswith("run") and rng.random() < 0.15:
        kind = "mpirun " + kind
    job["kind"] = kind
    if kind.startswith("extract"):
        options = common + threads + (["--domains", str(domains)] if not on_mesh else [])
        if kind.endswith("--reduce"):
            options += ["--reduce", "--max-error", rng.choice(["0.25", "0.25", "0.5", "0"]),
                        "--phi", rng.choice(["0.9", "0.9", "0.7", "0.98"])]
        command = [args.tetiso, "extract"] + options
    else:
        options = common + threads + ["--domains", str(domains), "--quiet"]
        if kind.endswith("--no-reduce"):
            options += ["--no-reduce"]
        else:
            options += ["--seam-rings", rng.choice(["1", "1", "0", "2"]),
                        "--sample-rings", rng.choice(["1", "1", "0", "-1", "2"]),
                        "--max-error", rng.choice(["0.25", "0.25", "0.5", "0"]),
                        "--phi", rng.choice(["0.9", "0.9", "0.7", "0.98"])]
        options += ["--device", "gpu" if args.gpu and rng.random() < 0.5 else "cpu"]
        command = [args.tetiso, "run"] + options
        if kind.startswith("mpirun"):
            command = [args.mpirun, "--oversubscribe", "-np", str(rng.choice([2, 3]))] + command
    job["command"] = command
    reduced = "--no-reduce" not in command and (kind.startswith(("run", "mpirun")) or "--reduce" in command)
    if reduced:
        # The raw surface of the same field and level, one domain.
        job["raw_command"] = [args.tetiso, "extract"] + common
        bound = command[command.index("--max-error") + 1]
        if not on_mesh and float(bound) > 0:
            job["bound"] = float(bound) * 5.0 / (n - 1)
    return job


def relative(command):
    """A command as run from the repository's root."""
    return command.replace(str(ROOT) + "/", "")


def run(command, timeout):
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout)


def check_job(job, tetiso, work, timeout):
    """Runs the job and checks its surface; returns the record."""
    out, raw = work / "out.ply", work / "raw.ply"
    for path in (out, raw):
        path.unlink(missing_ok=True)
    record = {k: job[k] for k in job if k not in ("command", "raw_command")}
    record["reproduce"] = [relative(shlex.join(job["command"] + ["-o", "out.ply"]))]
    started = time.monotonic()
    try:
        done = run(job["command"] + ["-o", str(out)], timeout)
        if done.returncode != 0:
            record.update(outcome="error", detail=(done.stderr.strip().splitlines() or ["no message"])[-1],
                          exit_status=done.returncode)
            return record
        checked = run([tetiso, "check", "--strict", str(out)], timeout)
        violations = [line.split(": ", 2)[-1] for line in checked.stderr.splitlines() if line.strip()]
        if checked.returncode not in (0, 1):
            violations.append(f"check failed with status {checked.returncode}")
        record["reproduce"].append("tetiso check --strict out.ply")
        if "raw_command" in job:
            done = run(job["raw_command"] + ["-o", str(raw)], timeout)
            record["reproduce"].append(relative(shlex.join(job["raw_command"] + ["-o", "raw.ply"])))
            if done.returncode != 0:
                violations.append("raw extraction failed: " + done.stderr.strip())
            else:
                against = run([tetiso, "check", "--strict", "--no-self-intersections", str(raw), "--against", str(out),
                               "--vertices-only"], timeout)
                record["reproduce"].append("tetiso check --strict --no-self-intersections raw.ply --against out.ply "
                                           "--vertices-only")
                violations += ["raw: " + line.split(": ", 2)[-1] for line in against.stderr.splitlines()
                               if line.strip()]
                report = json.loads(against.stdout)
                distance = report["against"]["hausdorff"]["forward"]
                record["raw_vertex_distance"] = distance
                if "bound" in job and distance > job["bound"] * (1 + 1e-5):
                    violations.append(f"error bound: a raw vertex lies {distance:.6g} from the surface, "
                                      f"over the bound {job['bound']:.6g}")
        record["outcome"] = "violations" if violations else "clean"
        if violations:
            record["violations"] = violations
        topology = json.loads(checked.stdout)["topology"]
        record["triangles"] = topology["triangles"]
    except subprocess.TimeoutExpired:
        record["outcome"] = "timeout"
    finally:
        record["seconds"] = round(time.monotonic() - started, 3)
    return record


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tetiso", default=str(ROOT / "build/core/tetiso"))
    parser.add_argument("--jobs", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--first", type=int, default=0, help="index of the first job")
    parser.add_argument("--minutes", type=float, default=0, help="stop drawing jobs after this long (0: never)")
    parser.add_argument("--max-lattice", type=int, default=24)
    parser.add_argument("--mpirun", default="", help="mpirun to run some jobs with 2 or 3 ranks")
    parser.add_argument("--gpu", action="store_true", help="run half the run jobs with --device gpu")
    parser.add_argument("--timeout", type=float, default=300)
    parser.add_argument("--json", help="write the campaign's record here")
    args = parser.parse_args()
    if not Path(args.tetiso).is_file():
        sys.exit(f"soak: --tetiso {args.tetiso}: no such file")
    if args.max_lattice < 5:
        sys.exit("soak: --max-lattice must be at least 5")
    # Threads that wait passively: on a loaded machine spinning ones cost a
    # job with two threads several times its time (no change to any surface).
    os.environ.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_WAIT_POLICY="passive")

    started = time.time()
    records = []
    with tempfile.TemporaryDirectory(prefix="tetiso-soak-") as folder:
        for index in range(args.first, args.first + args.jobs):
            if args.minutes and time.time() - started > 60 * args.minutes:
                break
            job = draw_job(args.seed, index, args)
            record = check_job(job, args.tetiso, Path(folder), args.timeout)
            if record["outcome"] == "clean":  # the seed and index reproduce it; keep the record small
                del record["reproduce"]
            records.append(record)
            if record["outcome"] != "clean":
                print(f"job {index}: {record['outcome']}: " + "; ".join(record.get("violations", [])) +
                      record.get("detail", "") + "\n  " + "\n  ".join(record["reproduce"]), flush=True)
    counts = {}
    for r in records:
        counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
    print(f"soak: {len(records)} jobs, seed {args.seed}: " +
          ", ".join(f"{v} {k}" for k, v in sorted(counts.items())), flush=True)
    if args.json:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True,
                                text=True).stdout.strip()
        cpu = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                    if line.startswith("model name")), platform.processor())
        Path(args.json).write_text(json.dumps({
            "command": relative(shlex.join(["tools/soak.py"] + sys.argv[1:])),
            "commit": commit, "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(started)),
            "seconds": round(time.time() - started, 1), "machine": f"{cpu}, {os.cpu_count()} CPUs",
            "tetiso": args.tetiso,
            "seed": args.seed, "jobs": len(records), "counts": counts, "records": records}, indent=1) + "\n")
    return 0 if counts.get("clean", 0) == len(records) else 1


if __name__ == "__main__":
    sys.exit(main())
