#!/usr/bin/env python3
"""Issue 17: warm frames of the speed workload, the current binary against commit ad4dc05.

Both binaries render the same files, TF, camera and turntable (3 degrees per frame) in one
process each, alternating per workload, rounds after rounds; the median warm frame (frames
after the first) is kept per run and the fastest run per workload reported, with the ratio.

  python3 docs/bench/vs_base.py --base BASE_VOLUX --new target/release/volux \
      --data /work/bench-data [--frames 8] [--rounds 2] [--only pt]

BASE_VOLUX is ad4dc05 built with docs/bench/base-harness.patch (VOLUX_BASE_FRAMES=N renders N
frames of the turntable and prints their times; ad4dc05 has no --orbit). DATA holds the output
of ../shared/bench/make_data.py, `camera.json` (the bench camera as a look-at file), the 37-knot
TF and `tf-dense.json` (every tet visible); run `--setup` once to write the last three.
"""
import argparse, json, math, os, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared"))


def setup(data):
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    cam = {"projection": "perspective", "fov_y_deg": 30, "eye": [7 * c * c, 7 * c * s, 7 * s],
           "target": [0, 0, 0], "up": [0, 0, 1]}
    json.dump(cam, open(os.path.join(data, "camera.json"), "w"))
    tf = json.load(open(os.path.join(SHARED, "bench", "tf-37-knots.json")))
    json.dump(tf, open(os.path.join(data, "tf-37-knots.json"), "w"))
    tf["extinction"] = [[0.0, 0.6], [0.5, 1.2], [1.0, 2.0]]
    json.dump(tf, open(os.path.join(data, "tf-dense.json"), "w"))
    ml = json.load(open(os.path.join(data, "ml_256.json")))
    side = {"kind": "grid", "dims_xyz": ml["dims"], "dtype": "float32", "endianness": "little",
            "spacing": ml["spacing"], "origin": ml["origin"], "value_range": ml["range"]}
    json.dump(side, open(os.path.join(data, "ml_256.f32.raw.json"), "w"))
    for name, rel, lo, hi in HEADS:
        path = os.path.join(data, f"camera-{name}.json")
        centre = [(a + b) / 2 for a, b in zip(lo, hi)]
        r = 1.9 * math.dist(lo, hi)
        az, el = math.radians(30), math.radians(20)
        d = [-math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)]
        cam = {"projection": "perspective", "fov_y_deg": 30,
               "eye": [c0 + r * di for c0, di in zip(centre, d)], "target": centre, "up": [0, 0, 1]}
        json.dump(cam, open(path, "w"))


HEADS = [("ct", "data/invesalius_cranium_ct/cranium_256x256x108_int16.raw.gz",
          [0, 0, 0], [244.042956, 244.042956, 160.5]),
         ("mri", "data/niivue_chris_t1/chris_t1_188x256x190_uint8.raw.gz",
          [0, 0, 0], [164.56, 224.4, 166.32])]


def workloads(data):
    cam = ["--camera", os.path.join(data, "camera.json"), "--size", "512x512"]
    tf = ["--tf", os.path.join(data, "tf-37-knots.json")]
    dense = ["--tf", os.path.join(data, "tf-dense.json")]
    pt = ["--method", "pt", "--color", "psi", "--sort", "centroid"]
    ray = ["--method", "raycast", "--integrator", "exact"]
    w = [("grid ml-256 riemann 0.5", os.path.join(data, "ml_256.f32.raw"), tf + cam + ["--step", "0.5"])]
    for name, rel, _, _ in HEADS:
        w.append((f"grid {name}-head riemann 0.5", os.path.join(SHARED, rel),
                  ["--camera", os.path.join(data, f"camera-{name}.json"), "--size", "512x512", "--step", "0.5"]))
    for m in ("200k", "1250k"):
        f = os.path.join(data, f"tets_{m}.vtk")
        w.append((f"pt {m}", f, pt + tf + cam))
        w.append((f"pt {m} dense", f, pt + dense + cam))
        w.append((f"tetray {m}", f, ray + tf + cam))
    return w


def run_base(exe, file, opts, frames):
    env = dict(os.environ, VOLUX_BASE_FRAMES=str(frames))
    out = subprocess.run([exe, "render", file, *opts, "-o", "/tmp/vs_base_base.png"], env=env,
                         capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"base failed: {out.stderr.strip()}")
    rec = json.loads(out.stdout.strip().splitlines()[-1])
    return rec["first_ms"], rec["warm_median_ms"]


def run_new(exe, file, opts, frames):
    out = subprocess.run([exe, "render", file, *opts, "--orbit", f"{frames}:3", "--no-write",
                          "--stats", "--json"], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"new failed: {out.stderr.strip()}")
    ms = [json.loads(l)["ms"] for l in out.stdout.splitlines() if l.startswith("{")]
    warm = sorted(ms[1:])
    return ms[0], warm[len(warm) // 2]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--base"), ap.add_argument("--new"), ap.add_argument("--data", required=True)
    ap.add_argument("--also", help="a third binary (today's CLI, e.g. an earlier build), timed too")
    ap.add_argument("--frames", type=int, default=8), ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--only", default=""), ap.add_argument("--setup", action="store_true")
    a = ap.parse_args()
    if a.setup:
        return setup(a.data)
    best = {}
    for r in range(a.rounds):
        for name, file, opts in workloads(a.data):
            if not all(w in name for w in a.only.split()):
                continue
            runs = [run_base(a.base, file, opts, a.frames)]
            if a.also:
                runs.append(run_new(a.also, file, opts, a.frames))
            runs.append(run_new(a.new, file, opts, a.frames))
            old = best.get(name, [(1e9, 1e9)] * len(runs))
            best[name] = [min(o, x, key=lambda t: t[1]) for o, x in zip(old, runs)]
            print(f"round {r} {name}: " + ", ".join(f"{x[1]:.1f}" for x in runs) + " ms",
                  file=sys.stderr, flush=True)
    also = " | also first / warm (ms) | now vs also" if a.also else ""
    print(f"| workload | ad4dc05 first / warm (ms){also.split(' | now')[0]} | now first / warm (ms) "
          f"| speed-up (warm){' | now vs also' if a.also else ''} |")
    print("|---|---:|---:|---:" + ("|---:|---:" if a.also else "") + "|")
    for name, runs in best.items():
        b, n = runs[0], runs[-1]
        cells = [f"{x[0]:.1f} / {x[1]:.1f}" for x in runs]
        extra = f" | {runs[1][1] / n[1]:.2f}x" if a.also else ""
        print(f"| {name} | {' | '.join(cells)} | {b[1] / n[1]:.2f}x{extra} |")


if __name__ == "__main__":
    main()
