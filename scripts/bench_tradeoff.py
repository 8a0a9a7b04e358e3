#!/usr/bin/env python3
"""Run time against error: the pipeline's cost per frame and its error against
the simulator's truth, for the shipped defaults, one setting changed at a
time, and the seed systems' methods, over simulated worlds and camera paths.

Each configuration runs `probelight run --source sim` once per (world, path).
From its report.json:
  - ms per frame: the sum over the pipeline's stages (upload, detect_pose,
    probe_to_cube, diffuse_*, glossy, clipped_rescale, shadows, render; not
    the simulator, not present) of median ms x runs / frames, i.e. what the
    stages cost per frame with their skips, on this machine; the fit of the
    lights at start-up (fit_lights + bracket_merge) is a column of its own;
  - irradiance error: accuracy.diffuse_irradiance_rel_error_vs_clipped (the
    truth monitor's median relative error of E over the 14 normals, against
    what an 8-bit camera can see);
  - pose error: accuracy.pose_rotation_error_deg.
The figures of a configuration are the means over the (world, path) runs.

Writes OUT/tradeoff.csv and, with gnuplot (Debian's gnuplot-nox), OUT/tradeoff.png:
every configuration, the Pareto front (no other is both faster and more
accurate), the shipped defaults and the seed baselines marked.

usage: scripts/bench_tradeoff.py [--quick] [--frames N] [--out DIR] [--probelight PATH]
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HDR = os.path.join(ROOT, "tests", "data", "env")

# Per frame (with their skips); the fit of the lights (fit_lights,
# bracket_merge) runs at a recalibration only and is reported apart.
PIPELINE_STAGES = ["upload", "detect_pose", "probe_to_cube", "diffuse_blur", "diffuse_sh9", "glossy",
                   "clipped_rescale", "shadows", "render"]
FIT_STAGES = ["fit_lights", "bracket_merge"]

# name -> (kind, {section: {field: value}}); kind: "default", "sweep" or "seed".
CONFIGS = [
    ("defaults", "default", {}),
    ("face_size 16", "sweep", {"environment_maps": {"face_size": 16, "glossy_levels": 0}}),  # glossy maps need >= 32
    ("face_size 32", "sweep", {"environment_maps": {"face_size": 32}}),
    ("face_size 128", "sweep", {"environment_maps": {"face_size": 128, "prefilter_face_size": 16}}),
    ("half_taps 8", "sweep", {"environment_maps": {"half_taps": 8}}),
    ("half_taps 12", "sweep", {"environment_maps": {"half_taps": 12}}),
    ("intermediate_rows 16", "sweep", {"environment_maps": {"intermediate_rows": 16}}),
    ("intermediate_rows 64", "sweep", {"environment_maps": {"intermediate_rows": 64}}),
    ("diffuse_face_size 8", "sweep", {"environment_maps": {"diffuse_face_size": 8}}),
    ("diffuse_face_size 32", "sweep", {"environment_maps": {"diffuse_face_size": 32}}),
    ("maps every frame", "sweep", {"map_updates": {"max_age_frames": 1}}),
    ("maps every 90 frames", "sweep", {"map_updates": {"max_age_frames": 90}}),
    ("lights 4", "sweep", {"lights": {"count": 4}}),
    ("lights 16", "sweep", {"lights": {"count": 16}}),
    ("shadow maps 128", "sweep", {"lights": {"shadow_map_size": 128, "ground_texture_size": 128}}),
    ("shadow maps 512", "sweep", {"lights": {"shadow_map_size": 512, "ground_texture_size": 512}}),
    ("seed C: SH9", "seed", {"environment_maps": {"diffuse_method": "sh9"}}),
    ("seed C: median cut 8", "seed", {"lights": {"placement": "median_cut"}}),
    ("seed B: fixed dome 8", "seed", {"lights": {"placement": "fixed"}}),
    ("seed B: fixed dome 64", "seed", {"lights": {"placement": "fixed", "count": 64}}),
]

WORLDS = ["studio", "sun_sky", os.path.join(HDR, "KernerEnvLatLong.exr"), os.path.join(HDR, "StageEnvLatLong.exr")]
PATHS = ["static", "slow_wobble", "orbit"]


def yaml_for(sections, world, path):
    lines = ["%YAML:1.0", "---"]
    merged = {k: dict(v) for k, v in sections.items()}
    merged.setdefault("sim", {}).update({"env": world, "camera_path": path})
    for section, fields in merged.items():
        lines.append(f"{section}:")
        for field, value in fields.items():
            text = f'"{value}"' if isinstance(value, str) else str(value)
            lines.append(f"  {field}: {text}")
    return "\n".join(lines) + "\n"


def run_one(probelight, sections, world, path, frames, work):
    config = os.path.join(work, "probelight.yaml")
    with open(config, "w") as f:
        f.write(yaml_for(sections, world, path))
    out = os.path.join(work, "run")
    shutil.rmtree(out, ignore_errors=True)
    result = subprocess.run([probelight, "run", "--source", "sim", "--frames", str(frames), "--save-every", "0",
                             "--quiet", "--config", config, "--out", out], capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{world} {path}: exit {result.returncode}: {result.stderr.strip()}")
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    stages = report["stages"]
    def total(names):
        return sum(stages[s]["median_ms"] * stages[s]["runs"] for s in names
                   if s in stages and stages[s]["median_ms"] is not None)
    accuracy = report.get("accuracy", {})
    return (total(PIPELINE_STAGES) / report["frames"], total(FIT_STAGES),
            accuracy.get("diffuse_irradiance_rel_error_vs_clipped"), accuracy.get("pose_rotation_error_deg"))


def pareto(rows):
    front = []
    for r in rows:
        if not any(o["ms"] <= r["ms"] and o["err"] <= r["err"] and (o["ms"] < r["ms"] or o["err"] < r["err"])
                   for o in rows):
            front.append(r)
    return sorted(front, key=lambda r: r["ms"])


def plot(out_dir, rows):
    if not shutil.which("gnuplot"):
        print("bench_tradeoff: no gnuplot (apt-get install gnuplot-nox): CSV only", file=sys.stderr)
        return
    data = os.path.join(out_dir, "tradeoff.dat")
    with open(data, "w") as f:
        for kind in ["sweep", "seed", "default", "front"]:
            chosen = pareto(rows) if kind == "front" else [r for r in rows if r["kind"] == kind]
            f.write(f"# {kind}\n")
            for r in chosen:
                f.write(f'{r["ms"]:.3f} {100 * r["err"]:.3f} "{r["name"]}"\n')
            f.write("\n\n")
    script = f"""
set terminal pngcairo size 1200,760 font ",10" noenhanced
set output "{os.path.join(out_dir, 'tradeoff.png')}"
set title "probelight: pipeline ms per frame against irradiance error (simulated worlds, this machine's llvmpipe)"
set xlabel "pipeline ms per frame (stages' median x runs / frames)"
set ylabel "irradiance error vs truth, median %"
set grid
set key top right
set offsets graph 0.02, graph 0.12, graph 0.05, graph 0.05
plot "{data}" index 0 using 1:2 with points pt 7 ps 1.2 lc rgb "#888888" title "one setting changed", \\
     "" index 0 using 1:2:3 with labels offset 0.6,0.6 left font ",8" tc rgb "#555555" notitle, \\
     "" index 1 using 1:2 with points pt 5 ps 1.4 lc rgb "#1f77b4" title "seed baselines", \\
     "" index 1 using 1:2:3 with labels offset 0.6,-0.8 left font ",8" tc rgb "#1f77b4" notitle, \\
     "" index 3 using 1:2 with lines lw 2 lc rgb "#2ca02c" title "Pareto front", \\
     "" index 2 using 1:2 with points pt 9 ps 2.2 lc rgb "#d62728" title "shipped defaults"
"""
    subprocess.run(["gnuplot"], input=script, text=True, check=True)
    os.remove(data)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="3 worlds (studio and both real HDR maps) x 2 moving paths (the full sweep: 4 x 3)")
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--out", default=os.path.join(ROOT, "out", "bench"))
    parser.add_argument("--probelight", default=os.path.join(ROOT, "build", "probelight"))
    parser.add_argument("--replot", action="store_true", help="draw OUT/tradeoff.png again from OUT/tradeoff.csv")
    args = parser.parse_args()
    if args.replot:
        with open(os.path.join(args.out, "tradeoff.csv")) as f:
            rows = [{"name": r["configuration"], "kind": r["kind"], "ms": float(r["ms_per_frame"]),
                     "err": float(r["irradiance_error_pct"]) / 100.0} for r in csv.DictReader(f)]
        plot(args.out, rows)
        return
    if not os.access(args.probelight, os.X_OK):
        sys.exit(f"bench_tradeoff: {args.probelight} not built (scripts/build.sh probelight)")
    worlds = [WORLDS[0]] + WORLDS[2:] if args.quick else WORLDS
    paths = PATHS[1:] if args.quick else PATHS
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for name, kind, sections in CONFIGS:
            runs = [run_one(args.probelight, sections, w, p, args.frames, work) for w in worlds for p in paths]
            errors = [e for _, _, e, _ in runs if e is not None]
            poses = [p for _, _, _, p in runs if p is not None]
            row = {"name": name, "kind": kind, "ms": sum(m for m, _, _, _ in runs) / len(runs),
                   "fit_ms": sum(f for _, f, _, _ in runs) / len(runs),
                   "err": sum(errors) / len(errors) if errors else float("nan"),
                   "pose": sum(poses) / len(poses) if poses else float("nan")}
            rows.append(row)
            print(f"{name:28s} {row['ms']:7.2f} ms/frame  fit {row['fit_ms']:6.0f} ms  irradiance {100 * row['err']:5.2f}%"
                  f"  pose {row['pose']:.3f} deg", flush=True)
    front = {r["name"] for r in pareto(rows)}
    with open(os.path.join(args.out, "tradeoff.csv"), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["configuration", "kind", "ms_per_frame", "fit_ms", "irradiance_error_pct", "pose_error_deg",
                         "pareto"])
        for r in rows:
            writer.writerow([r["name"], r["kind"], f"{r['ms']:.3f}", f"{r['fit_ms']:.1f}", f"{100 * r['err']:.3f}",
                             f"{r['pose']:.4f}", "yes" if r["name"] in front else "no"])
    plot(args.out, rows)
    print(f"bench_tradeoff: {len(worlds)} worlds x {len(paths)} paths x {args.frames} frames; "
          f"{os.path.join(args.out, 'tradeoff.csv')}")


if __name__ == "__main__":
    main()
