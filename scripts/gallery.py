#!/usr/bin/env python3
"""A gallery of camera frames with the doors found drawn on them (issue 21):
simulates RGB-D frames (door_scene_sim --sensor rgbd --robot-camera, one
row per depth family), runs door_state_cli on each (--up auto) and writes
one PNG: each tile is the frame's depth (near light, far dark, no return
black), the true leaf outlined in thin white, each door found drawn as its
leaf in the colour of its state (closed green, semi-open yellow, open red,
not closed blue) with its hinge as a short vertical bar. A caption file
next to the PNG (.txt) names every tile with what was found and what is
true.

  scripts/gallery.py [--out doc/gallery.png] [--first-seed S] [--per-row N]
                     [--models default,structured,tof,stereo] [--scale K]

Needs only numpy (scripts/install_deps.sh installs it).
"""
import argparse, json, os, struct, subprocess, tempfile, zlib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
BIN = Path(os.environ["DSR_BIN"]) if os.environ.get("DSR_BIN") else Path(os.environ.get("DSR_BUILD", REPO / "build")) / "bin"
COLOURS = {"closed": (40, 200, 60), "semi_open": (250, 210, 0), "open": (240, 40, 40), "not_closed": (60, 140, 255)}


def read_pcd(path):
    """An organized binary PCD of door_scene_sim: (H, W, 3) float xyz, NaN where no return."""
    with open(path, "rb") as f:
        header = {}
        while True:
            line = f.readline().decode("ascii").strip()
            if not line or line.startswith("#"):
                continue
            key, _, value = line.partition(" ")
            header[key] = value.split()
            if key == "DATA":
                break
        if header["DATA"][0] != "binary":
            raise SystemExit(f"{path}: DATA {header['DATA'][0]} (binary expected)")
        w, h = int(header["WIDTH"][0]), int(header["HEIGHT"][0])
        dtype = np.dtype([(n, {"F": "f", "U": "u", "I": "i"}[t] + s) for n, t, s in
                          zip(header["FIELDS"], header["TYPE"], header["SIZE"])])
        data = np.frombuffer(f.read(dtype.itemsize * w * h), dtype=dtype)
    return np.stack([data["x"], data["y"], data["z"]], axis=-1).reshape(h, w, 3).astype(np.float64)


def fit_intrinsics(xyz):
    """fx, fy, cx, cy by least squares over the pixels with a return."""
    h, w, _ = xyz.shape
    v, u = np.mgrid[0:h, 0:w]
    ok = np.isfinite(xyz).all(axis=2) & (xyz[..., 2] > 0.05)
    a, b = xyz[ok][:, 0] / xyz[ok][:, 2], xyz[ok][:, 1] / xyz[ok][:, 2]
    fx, cx = np.linalg.lstsq(np.stack([a, np.ones_like(a)], 1), u[ok], rcond=None)[0]
    fy, cy = np.linalg.lstsq(np.stack([b, np.ones_like(b)], 1), v[ok], rcond=None)[0]
    return fx, fy, cx, cy


def depth_image(xyz, scale):
    z = xyz[::scale, ::scale, 2]
    ok = np.isfinite(z)
    far = np.percentile(z[ok], 98) if ok.any() else 1.0
    g = np.where(ok, 230 - 200 * np.clip(z / max(far, 1e-3), 0, 1), 0).astype(np.uint8)
    return np.repeat(g[..., None], 3, axis=2).copy()


def draw_segment(img, p, q, k, colour, width):
    """The 3D segment p-q (camera frame) projected with k = (fx, fy, cx, cy), clipped in front."""
    near = 0.05
    if p[2] < near and q[2] < near:
        return
    if p[2] < near or q[2] < near:
        t = (near - p[2]) / (q[2] - p[2])
        c = p + t * (q - p)
        p, q = (c, q) if p[2] < near else (p, c)
    fx, fy, cx, cy = k
    a = np.array([fx * p[0] / p[2] + cx, fy * p[1] / p[2] + cy])
    b = np.array([fx * q[0] / q[2] + cx, fy * q[1] / q[2] + cy])
    h, w, _ = img.shape
    n = int(min(4 * (h + w), max(2, np.abs(b - a).max() * 2)))
    for t in np.linspace(0, 1, n):
        x, y = a + t * (b - a)
        xi, yi = int(round(x)), int(round(y))
        r = width // 2
        if -r <= xi < w + r and -r <= yi < h + r:
            img[max(0, yi - r):max(0, yi + r + 1), max(0, xi - r):max(0, xi + r + 1)] = colour


def draw_leaf(img, corners, k, colour, width):
    c = [np.asarray(x, dtype=float) for x in corners]
    for i in range(4):
        draw_segment(img, c[i], c[(i + 1) % 4], k, colour, width)


def write_png(path, img):
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(REPO / "doc" / "gallery.png"))
    ap.add_argument("--first-seed", type=int, default=3000)
    ap.add_argument("--per-row", type=int, default=4)
    ap.add_argument("--models", default="default,structured,tof,stereo")
    ap.add_argument("--scale", type=int, default=2, help="every K-th pixel of the frame")
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="dsr_gallery_"))
    rows, captions = [], []
    for model in args.models.split(","):
        tiles = []
        for seed in range(args.first_seed, args.first_seed + args.per_row):
            prefix = work / f"{model}_{seed}"
            sim = [str(BIN / "door_scene_sim"), "--quiet", "--sensor", "rgbd", "--robot-camera", "--seed", str(seed),
                   "--out", str(prefix), "--formats", "pcd,json"]
            sim += ["--depth-model", model] if model != "default" else []
            subprocess.run(sim, check=True)
            subprocess.run([str(BIN / "door_state_cli"), "--quiet", "--up", "auto", "--json", f"{prefix}.report.json",
                            f"{prefix}.pcd"], check=True)
            xyz = read_pcd(f"{prefix}.pcd")
            truth = json.load(open(f"{prefix}.json"))
            report = json.load(open(f"{prefix}.report.json"))
            fx, fy, cx, cy = fit_intrinsics(xyz)
            s = args.scale
            k = (fx / s, fy / s, (cx + 0.5) / s - 0.5, (cy + 0.5) / s - 0.5)
            img = depth_image(xyz, s)
            for d in truth["doors"]:
                draw_leaf(img, d["leaf_corners"], k, (255, 255, 255), 1)
            for d in report["doors"]:
                colour = COLOURS.get(d["state"], (255, 0, 255))
                draw_leaf(img, d["leaf_corners"], k, colour, 3)
                hinge = np.asarray(d["hinge"], dtype=float)
                up = np.asarray(report["up"], dtype=float)
                draw_segment(img, hinge, hinge + 0.3 * up, k, colour, 5)
            tiles.append(img)
            found = ", ".join(f"{d['state']} {d['opening_angle_deg']:.0f} deg" for d in report["doors"]) or "no door"
            true = ", ".join(f"{d['state']} {d['opening_angle_deg']:.0f} deg" for d in truth["doors"] if d.get("in_view"))
            captions.append(f"{model} seed {seed}: found {found}; true (in view) {true or 'none'}")
        h = max(t.shape[0] for t in tiles)
        rows.append(np.concatenate([np.pad(t, ((0, h - t.shape[0]), (0, 4), (0, 0)), constant_values=255)
                                    for t in tiles], axis=1))
    w = max(r.shape[1] for r in rows)
    grid = np.concatenate([np.pad(r, ((0, 4), (0, w - r.shape[1]), (0, 0)), constant_values=255) for r in rows], axis=0)
    write_png(args.out, grid)
    Path(args.out).with_suffix(".txt").write_text(
        "Rows (depth families, door_scene_sim --robot-camera): " + args.models + "\n" + "\n".join(captions) + "\n")
    print(f"wrote {args.out} ({grid.shape[1]} x {grid.shape[0]}) and {Path(args.out).with_suffix('.txt')}")


if __name__ == "__main__":
    main()
