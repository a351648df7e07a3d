#!/usr/bin/env python3
"""The scan table: `skinstream build-subject --mesh SCAN` on scans made from the template in the key
poses of a synthetic range-of-motion take, against real takes, as one Markdown table (a row per
pose, a column per take: the take's longest stretched edge against the refusal limit, the template's
fit to the scan, the markers the fit could not place; or why the subject was refused).

Usage: scripts/scan_table.py [--skinstream build/bin/skinstream] [--data ../shared/data/captures]
                             [--json-out runs.json] [--keep DIR]
A scan: the truth mesh of a key pose of `skinstream synth --motion rom` (the MakeHuman body posed,
with its muscle bulge and breathing: A pose, arms forward, overhead, out, crossed, a side bend, a leg
out, ...), written in another unit and up axis each time (centimetres Y up, metres Z up, millimetres
Y up, decimetres X up) with its vertices shuffled, so that nothing of the template's own order,
pose, unit or axes reaches the builder. A scan the builder refuses is a subject lost; a subject
built is measured by how far its training take comes from the stretch limit (the longest stretched
edge over the frames checked, in typical edges: the reference mesh's median edge; the limit is 25).
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile

import numpy as np

TAKES = [
    ("CMU 85_02", "cmu/85_02.c3d"),
    ("HDM05 bd_05-01", "hdm05/HDM_bd_05-01_01_120.c3d"),
    ("tennis serve (50 Hz)", "kineticstoolkit/kinematics_tennis_serve.c3d"),
]

# (name, millimetres per unit, rotation from skinstream axes (Z up, facing +Y) to the file's).
FRAMES = [
    ("cm, Y up", 10.0, np.array([[-1, 0, 0], [0, 0, 1], [0, 1, 0]], float)),
    ("m, Z up", 1000.0, np.eye(3)),
    ("mm, Y up", 1.0, np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)),
    ("dm, X up", 100.0, np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)),
]


def read_ply(path):
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            header += f.readline()
        lines = header.decode().splitlines()
        vertices = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
        faces = int(next(l for l in lines if l.startswith("element face")).split()[2])
        xyz = np.frombuffer(f.read(12 * vertices), dtype="<f4").reshape(vertices, 3).astype(float)
        tris = []
        for _ in range(faces):
            n = f.read(1)[0]
            idx = struct.unpack("<%di" % n, f.read(4 * n))
            for k in range(1, n - 1):  # a fan: quads become two triangles
                tris.append((idx[0], idx[k], idx[k + 1]))
    return xyz, np.array(tris, dtype=np.int32)


def write_ply(path, xyz, tris):
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                 "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(xyz), len(tris))).encode())
        f.write(xyz.astype("<f4").tobytes())
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))


# The scans' poses: key poses of the synthetic range-of-motion take (core/synth/motion_rom.cpp),
# by their time in it (seconds at its natural speed).
POSES = [
    ("A pose (the template's rest)", 0.0),
    ("arms forward", 1.2),
    ("arms overhead", 2.4),
    ("arms out, above horizontal", 3.6),
    ("double biceps", 4.8),
    ("arms at the sides, elbows bent", 6.0),
    ("arms crossed", 7.2),
    ("side bend, left arm up", 10.2),
    ("right leg out", 18.2),
]


def make_scans(skinstream, folder):
    meshes = os.path.join(folder, "truth")
    subprocess.run([skinstream, "synth", "--motion", "rom", "--seconds", "20", "--seed", "11", "--markers", "41",
                    "--out", os.path.join(folder, "rom.c3d"), "--mesh-out-every", "12", meshes],
                   check=True, stdout=subprocess.DEVNULL)
    scans = []
    rng = np.random.default_rng(5)
    for k, (label, seconds) in enumerate(POSES):
        xyz, tris = read_ply(os.path.join(meshes, "mesh_%06d.ply" % round(seconds * 120)))
        unit_name, mm, rotation = FRAMES[k % len(FRAMES)]
        order = rng.permutation(len(xyz))  # scan vertex i is truth vertex order[i]
        where = np.empty_like(order)
        where[order] = np.arange(len(order))
        path = os.path.join(folder, "scan_%02d.ply" % k)
        write_ply(path, (xyz[order] @ rotation.T) / mm, where[tris])
        scans.append(("%s (%s)" % (label, unit_name), path))
    return scans


def build(skinstream, capture, scan, out):
    run = subprocess.run([skinstream, "build-subject", "--capture", capture, "--mesh", scan, "--out", out],
                         capture_output=True, text=True)
    if run.returncode != 0:
        return {"built": False, "problem": (run.stderr.strip().splitlines() or ["exit %d" % run.returncode])[-1]}
    report = json.loads(run.stdout)
    checks = report["actor"]["checks"]
    through = report["mesh"]["through_the_template"]
    longest = checks.get("take_longest_stretched_edge", {}).get("typical_edges")
    return {"built": True, "fit_rms_mm": through["template_fit_rms_mm"], "arm_elevation_deg": through["arm_elevation_deg"],
            "take_longest_stretched_edge": longest, "unplaced": len(checks["unplaced_markers"])}


def cell(result):
    if not result["built"]:
        problem = result["problem"].replace("skinstream: error: ", "").replace("refused, nothing written: ", "")
        return "refused: " + problem.split(" (")[0]
    longest = result["take_longest_stretched_edge"]
    stretch = "%.1f" % longest if longest is not None else "built"
    return "%s (fit %.1f mm, %d not placed)" % (stretch, result["fit_rms_mm"], result["unplaced"])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--skinstream", default="build/bin/skinstream")
    parser.add_argument("--data", default="../shared/data/captures")
    parser.add_argument("--json-out", help="also write every run's result here")
    parser.add_argument("--keep", help="make the scans in this folder and keep them (default: a temporary one)")
    args = parser.parse_args()
    runs = []
    with tempfile.TemporaryDirectory() as temporary:
        folder = args.keep or temporary
        os.makedirs(folder, exist_ok=True)
        scans = make_scans(args.skinstream, folder)
        for label, capture in TAKES:
            for scan_label, scan in scans:
                result = build(args.skinstream, os.path.join(args.data, capture), scan, os.path.join(folder, "s.sksubj"))
                result.update({"take": label, "scan": scan_label})
                runs.append(result)
                print(json.dumps(result), file=sys.stderr)
    if args.json_out:
        with open(args.json_out, "w") as f:
            json.dump(runs, f, indent=1)
    print("Each cell: the training take's longest stretched edge (typical edges; refused over 25), the template's fit")
    print("to the scan (RMS) and the take's markers the fit could not place; or why the subject was refused.\n")
    print("| scan pose (unit, up axis) | " + " | ".join(label for label, _ in TAKES) + " |")
    print("|---" * (len(TAKES) + 1) + "|")
    for scan_label, _ in scans:
        cells = [cell(next(r for r in runs if r["take"] == label and r["scan"] == scan_label)) for label, _ in TAKES]
        print("| %s | %s |" % (scan_label, " | ".join(cells)))
    built = sum(1 for r in runs if r["built"])
    print("\nbuilt %d of %d" % (built, len(runs)))


if __name__ == "__main__":
    main()
