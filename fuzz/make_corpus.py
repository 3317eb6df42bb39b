#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz targets into fuzz/corpus/<target>/.

    /usr/bin/python3 fuzz/make_corpus.py [--sim build/bin/door_scene_sim]

Deterministic. The reader seeds are small, real-looking PCD (ascii, binary,
binary_compressed, float64, organized, empty) and PLY (ascii, binary little and
big endian, a face element before the vertices) files; the PointCloud2 seeds
are valid and nearly valid messages in fuzz_pointcloud2's input encoding; the
pipeline seeds are simulated scans (a laser scan of a room, a camera frame
thinned to 64x48) and small degenerate clouds in fuzz_pipeline's encoding.
The simulated scans need door_scene_sim (`make build`); without it those two
seeds are left as they are.
"""
import argparse
import math
import os
import random
import struct
import subprocess
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "corpus"


def lzf_compress(data: bytes) -> bytes:
    """LZF (liblzf's format, as pcl::lzfDecompress reads it), greedy matching."""
    out, lit, table, i, n = bytearray(), bytearray(), {}, 0, len(data)

    def flush():
        nonlocal lit
        while lit:
            chunk, lit = lit[:32], lit[32:]
            out.append(len(chunk) - 1)
            out.extend(chunk)

    while i < n:
        ref = None
        if i + 3 <= n:
            key = data[i:i + 3]
            ref = table.get(key)
            table[key] = i
        if ref is not None and i - ref - 1 < 8192:
            off, length, maxl = i - ref - 1, 3, min(264, n - i)
            while length < maxl and data[ref + length] == data[i + length]:
                length += 1
            flush()
            code = length - 2
            if code < 7:
                out.append((code << 5) | (off >> 8))
            else:
                out.append((7 << 5) | (off >> 8))
                out.append(code - 7)
            out.append(off & 0xFF)
            i += length
        else:
            lit.append(data[i])
            i += 1
    flush()
    return bytes(out)


def room_points(n, rnd):
    """n points on the floor, ceiling and walls of a 4 x 3 x 2.5 m room around the origin."""
    pts = []
    for _ in range(n):
        face = rnd.randrange(6)
        u, v = rnd.uniform(-1, 1), rnd.uniform(-1, 1)
        if face == 0: p = (2.0 * u, 1.5 * v, -1.2)
        elif face == 1: p = (2.0 * u, 1.5 * v, 1.3)
        elif face == 2: p = (2.0, 1.5 * u, 1.25 * v + 0.05)
        elif face == 3: p = (-2.0, 1.5 * u, 1.25 * v + 0.05)
        elif face == 4: p = (2.0 * u, 1.5, 1.25 * v + 0.05)
        else: p = (2.0 * u, -1.5, 1.25 * v + 0.05)
        pts.append(tuple(round(c + rnd.gauss(0, 0.003), 4) for c in p))
    return pts


def pcd_header(fields, sizes, types, counts, width, height, data):
    return ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
            f"FIELDS {' '.join(fields)}\nSIZE {' '.join(map(str, sizes))}\nTYPE {' '.join(types)}\n"
            f"COUNT {' '.join(map(str, counts))}\nWIDTH {width}\nHEIGHT {height}\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {width * height}\nDATA {data}\n").encode()


def reader_seeds(rnd):
    pts = room_points(24, rnd)
    seeds = {}
    # ascii with rgb, a comment, CRLF line ends and NaN spellings
    rows = [f"{x} {y} {z} {rnd.randrange(1 << 24)}" for x, y, z in pts] + ["nan nan nan 0"]
    seeds["pcd_ascii.pcd"] = pcd_header(["x", "y", "z", "rgb"], [4] * 4, ["F", "F", "F", "U"], [1] * 4,
                                        len(rows), 1, "ascii").replace(b"\n", b"\r\n") + \
        ("\r\n".join(rows) + "\r\n").encode()
    # organized 4 x 3, ascii, with NaN
    grid = pts[:11] + [(math.nan,) * 3]
    seeds["pcd_organized_ascii.pcd"] = pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 4, 3, "ascii") + \
        "".join(f"{x} {y} {z}\n" for x, y, z in grid).encode()
    # binary x y z label (what door_scene_sim writes)
    body = b"".join(struct.pack("<fffI", *p, i % 3) for i, p in enumerate(pts))
    seeds["pcd_binary.pcd"] = pcd_header(["x", "y", "z", "label"], [4] * 4, ["F", "F", "F", "U"], [1] * 4,
                                         len(pts), 1, "binary") + body
    # binary, float64 xyz after a 2 x uint16 field
    body = b"".join(struct.pack("<HHddd", 7, 9, *p) for p in pts)
    seeds["pcd_binary_f64.pcd"] = pcd_header(["ring", "x", "y", "z"], [2, 8, 8, 8], ["U", "F", "F", "F"],
                                             [2, 1, 1, 1], len(pts), 1, "binary") + body
    # binary_compressed: column-major x..., y..., z..., label..., LZF with back-references
    cols = [b"".join(struct.pack("<f", p[a]) for p in pts) for a in range(3)]
    cols.append(b"".join(struct.pack("<I", i % 2) for i in range(len(pts))))
    raw = b"".join(cols)
    packed = lzf_compress(raw)
    seeds["pcd_binary_compressed.pcd"] = pcd_header(["x", "y", "z", "label"], [4] * 4, ["F", "F", "F", "U"],
                                                    [1] * 4, len(pts), 1, "binary_compressed") + \
        struct.pack("<II", len(packed), len(raw)) + packed
    seeds["pcd_empty.pcd"] = pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 0, 1, "binary")
    # PLY: a face element (list property) before the vertices in the ascii one
    head = lambda fmt, n, extra="": (f"ply\nformat {fmt} 1.0\ncomment seed\n{extra}element vertex {n}\n"
                                     "property float x\nproperty float y\nproperty float z\n"
                                     "property uchar red\nend_header\n").encode()
    faces = "element face 2\nproperty list uchar int vertex_indices\n"
    seeds["ply_ascii.ply"] = head("ascii", len(pts), faces) + b"3 0 1 2\n4 0 1 2 3\n" + \
        "".join(f"{x} {y} {z} {i % 256}\n" for i, (x, y, z) in enumerate(pts)).encode()
    seeds["ply_binary_le.ply"] = head("binary_little_endian", len(pts)) + \
        b"".join(struct.pack("<fffB", *p, i) for i, p in enumerate(pts))
    seeds["ply_binary_be.ply"] = (f"ply\nformat binary_big_endian 1.0\nelement face 1\n"
                                  "property list uchar int vertex_indices\n"
                                  f"element vertex {len(pts)}\nproperty double x\nproperty double y\n"
                                  "property double z\nend_header\n").encode() + \
        struct.pack(">Biii", 3, 0, 1, 2) + b"".join(struct.pack(">ddd", *p) for p in pts)
    # Text clouds: S3DIS's "x y z r g b" lines; CloudCompare's export with its header; a .pts count line.
    seeds["text_s3dis.txt"] = "".join(f"{x} {y} {z} {i % 256} 128 64\n" for i, (x, y, z) in enumerate(pts)).encode()
    seeds["text_pts.pts"] = (f"{len(pts)}\n//X,Y,Z\n" +
                             "".join(f"{x},{y};{z}\t-1200\n" for x, y, z in pts)).encode()
    seeds["obj_mesh.obj"] = ("# seed\nmtllib m.mtl\no room\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in pts) +
                             "vn 0 0 1\nusemtl m\nf 1//1 2//1 3//1\n").encode()
    return seeds


# fuzz_pointcloud2's encoding (see fuzz_pointcloud2.cpp): mode byte, then with mode bits
# 2|4|8 set every step, offset and count is one byte; with bit 16 the sizes are made
# consistent: height byte, then the data, width = len(data) / (height * point_step).
F32, F64, U8, U16, U32 = 7, 8, 2, 4, 6
NAMES = {"x": 0, "y": 1, "z": 2, "rgb": 3, "intensity": 4}


def pc2(fields, point_step, height, data, big_endian=False):
    mode = 2 | 4 | 8 | 16 | (1 if big_endian else 0)
    out = bytearray([mode, point_step, len(fields)])
    for name, offset, datatype, count in fields:
        out += bytes([NAMES[name], offset, datatype, count])
    out.append(height)
    return bytes(out + data)


def pc2_seeds(rnd):
    pts = room_points(12, rnd)
    xyz = [("x", 0, F32, 1), ("y", 4, F32, 1), ("z", 8, F32, 1)]
    seeds = {
        "xyz_f32.bin": pc2(xyz, 12, 1, b"".join(struct.pack("<fff", *p) for p in pts)),
        "xyzrgb_padded_organized.bin": pc2(xyz + [("rgb", 16, F32, 1)], 32, 3,
                                           b"".join(struct.pack("<fffIf12x", *p, 0, 1.0) for p in pts)),
        "xyz_f64_intensity.bin": pc2([("intensity", 0, U16, 1), ("x", 8, F64, 1), ("y", 16, F64, 1),
                                      ("z", 24, F64, 1)], 32, 2,
                                     b"".join(struct.pack("<H6xddd", 5, *p) for p in pts)),
        "big_endian.bin": pc2(xyz, 12, 1, b"".join(struct.pack(">fff", *p) for p in pts), big_endian=True),
        "missing_z.bin": pc2(xyz[:2], 12, 1, b"".join(struct.pack("<fff", *p) for p in pts)),
        "x_as_uint8.bin": pc2([("x", 0, U8, 1)] + xyz[1:], 12, 1, b"".join(struct.pack("<fff", *p) for p in pts)),
    }
    return seeds


# fuzz_pipeline's encoding (see fuzz_pipeline.cpp): up index (+z -z +y -y +x -x auto),
# mode byte (bit 0: int16 coordinates times 1e-3 * (1 + mode >> 4) m, else raw float32;
# bit 1: viewpoint as 3 int8 decimetres; bit 2: organized; bit 3: reconstruction),
# width - 1 of an organized cloud, then the points.
def pipe(up, mode, width, pts, viewpoint=None):
    out = bytearray([up, mode, width - 1])
    if viewpoint is not None:
        out += struct.pack("<bbb", *viewpoint)
    for p in pts:
        if mode & 1:
            out += struct.pack("<hhh", *(max(-32768, min(32767, round(c / (1e-3 * (1 + (mode >> 4)))))) for c in p))
        else:
            out += struct.pack("<fff", *p)
    return bytes(out)


def read_sim_pcd(path):
    """x, y, z of door_scene_sim's binary PCD (x y z label, float32 x3 + uint32)."""
    blob = Path(path).read_bytes()
    head, _, body = blob.partition(b"DATA binary\n")
    width = int(head.split(b"WIDTH ")[1].split()[0])
    n = len(body) // 16
    return [struct.unpack_from("<fff", body, 16 * i) for i in range(n)], width


def pipeline_seeds(rnd, sim):
    seeds = {
        "room_synthetic_int16.bin": pipe(0, 1 | 8, 1, room_points(3000, rnd)),
        "plane_only_auto.bin": pipe(6, 1, 1, [(rnd.uniform(-2, 2), rnd.uniform(-2, 2), -1.2) for _ in range(800)]),
        "five_points_float.bin": pipe(0, 8, 1, [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (math.nan, 1, 1)]),
        "line_y_up_viewpoint.bin": pipe(3, 1 | 2, 1, [(0.01 * i, -0.5, 1.0) for i in range(300)], (5, -3, 0)),
    }
    if sim and os.access(sim, os.X_OK):
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run([sim, "--out", f"{tmp}/tls", "--scene", "paper_livingroom", "--points", "20000",
                            "--quiet"], check=True)
            pts, _ = read_sim_pcd(f"{tmp}/tls.pcd")
            pts = [p for p in pts if all(map(math.isfinite, p))]
            rnd.shuffle(pts)
            seeds["sim_livingroom_tls_4096.bin"] = pipe(0, 1 | 8, 1, pts[:4096])
            subprocess.run([sim, "--out", f"{tmp}/cam", "--sensor", "rgbd", "--seed", "3", "--quiet"], check=True)
            pts, width = read_sim_pcd(f"{tmp}/cam.pcd")  # 640 x 480, optical frame (up -y)
            thin = [pts[r * width + c] for r in range(0, 480, 10) for c in range(0, 640, 10)]
            seeds["sim_rgbd_64x48_organized.bin"] = pipe(3, 4 | 8, 64, thin)  # raw float32: NaN kept
    return seeds


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim", default=str(HERE.parent / "build" / "bin" / "door_scene_sim"))
    args = ap.parse_args()
    rnd = random.Random(6)
    for target, seeds in (("fuzz_cloud_reader", reader_seeds(rnd)), ("fuzz_pointcloud2", pc2_seeds(rnd)),
                          ("fuzz_pipeline", pipeline_seeds(rnd, args.sim))):
        d = OUT / target
        d.mkdir(parents=True, exist_ok=True)
        for name, blob in seeds.items():
            (d / name).write_bytes(blob)
            print(f"{d.relative_to(HERE.parent)}/{name}: {len(blob)} bytes")


if __name__ == "__main__":
    main()
