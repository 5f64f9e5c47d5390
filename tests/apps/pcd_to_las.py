#!/usr/bin/env python3
"""Converts a binary PCD with double x, y, z (what `rowloc world` writes) to an uncompressed LAS file.

The LAS file is written here from the specification (ASPRS 2019, LAS Specification 1.4 R15: the
public header block and the point data records of formats 0-10), independently of
rowloc's own writer (mapping/src/las_file.cpp), so that the command-line tests read LAS files that
rowloc did not write. Standard library only.

  pcd_to_las.py IN.pcd OUT.las [--shift DX DY DZ] [--version 1.2|1.3|1.4] [--format 0-10]
                [--scale S] [--extra-bytes N] [--laszip-bit]

--shift adds a constant to every point (e.g. 500000 5000000 0: local metres to UTM-sized
coordinates), --scale is the LAS scale factor of every axis (default 0.001 m), the offset is the
floor of the shifted minimum; --laszip-bit sets bit 7 of the point data record format byte, as
LASzip does (the file is not compressed: it tests the refusal).
"""
import argparse
import array
import math
import struct
import sys

RECORD_SIZES = [20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67]
HEADER_SIZES = {2: 227, 3: 235, 4: 375}


def read_binary_pcd(path):
    with open(path, "rb") as f:
        data = f.read()
    header = {}
    at = 0
    while True:
        end = data.index(b"\n", at)
        line = data[at:end].decode("ascii").strip()
        at = end + 1
        if not line or line.startswith("#"):
            continue
        key, _, value = line.partition(" ")
        header[key] = value.split()
        if key == "DATA":
            break
    if header["DATA"] != ["binary"] or header["FIELDS"] != ["x", "y", "z"] or header["SIZE"] != ["8", "8", "8"] \
            or header["TYPE"] != ["F", "F", "F"]:
        sys.exit(f"{path}: expected a binary PCD with double x y z only")
    count = int(header["POINTS"][0])
    values = array.array("d")
    values.frombytes(data[at:at + 24 * count])
    if sys.byteorder != "little":
        values.byteswap()
    return [(values[3 * i], values[3 * i + 1], values[3 * i + 2]) for i in range(count)]


def write_las(points, path, minor, point_format, scale, extra_bytes, laszip_bit):
    if point_format >= 6 and minor < 4 or point_format >= 4 and minor < 3:
        sys.exit(f"point format {point_format} is not a LAS 1.{minor} format")
    header_size = HEADER_SIZES[minor]
    record = RECORD_SIZES[point_format] + extra_bytes
    n = len(points)
    offset = [math.floor(min(p[axis] for p in points)) for axis in range(3)]
    counts = [[round((p[axis] - offset[axis]) / scale) for axis in range(3)] for p in points]
    lo = [min(c[axis] for c in counts) * scale + offset[axis] for axis in range(3)]
    hi = [max(c[axis] for c in counts) * scale + offset[axis] for axis in range(3)]

    body = bytearray(n * record)
    xyz = struct.Struct("<iii")
    return_byte = 0x09 if point_format < 6 else 0x11  # return 1 of 1 (3+3 or 4+4 bits)
    for i, c in enumerate(counts):
        xyz.pack_into(body, i * record, *c)
        body[i * record + 14] = return_byte
        body[i * record + (15 if point_format < 6 else 16)] = 2  # ground, any class will do

    legacy_count = n if minor < 4 or point_format < 6 else 0
    format_byte = point_format | (0x80 if laszip_bit else 0)
    global_encoding = 0x10 if point_format >= 6 else 0  # WKT, required with formats 6-10
    head = struct.pack("<4sHHIHH8sBB32s32sHHHIIBHI5I3d3d6d",
                       b"LASF", 0, global_encoding, 0, 0, 0, bytes(8), 1, minor,
                       b"OTHER", b"pcd_to_las.py (rowloc tests)", 1, 2026, header_size, header_size, 0,
                       format_byte, record, legacy_count, legacy_count, 0, 0, 0, 0,
                       scale, scale, scale, *offset, hi[0], lo[0], hi[1], lo[1], hi[2], lo[2])
    if minor >= 3:
        head += struct.pack("<Q", 0)  # start of waveform data packet record
    if minor >= 4:
        head += struct.pack("<QIQ15Q", 0, 0, n, n, *([0] * 14))
    assert len(head) == header_size, len(head)
    with open(path, "wb") as f:
        f.write(head)
        f.write(body)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("input")
    parser.add_argument("output")
    parser.add_argument("--shift", type=float, nargs=3, default=[0.0, 0.0, 0.0])
    parser.add_argument("--version", choices=["1.2", "1.3", "1.4"], default="1.4")
    parser.add_argument("--format", type=int, choices=range(11), default=6)
    parser.add_argument("--scale", type=float, default=0.001)
    parser.add_argument("--extra-bytes", type=int, default=0)
    parser.add_argument("--laszip-bit", action="store_true")
    args = parser.parse_args()
    points = [(x + args.shift[0], y + args.shift[1], z + args.shift[2]) for x, y, z in read_binary_pcd(args.input)]
    if not points:
        sys.exit(f"{args.input}: no points")
    write_las(points, args.output, int(args.version[2]), args.format, args.scale, args.extra_bytes, args.laszip_bit)
    print(f"{args.output}: {len(points)} points, LAS {args.version} format {args.format}")


if __name__ == "__main__":
    main()
