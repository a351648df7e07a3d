#!/usr/bin/env python3
"""An independent C3D reader, written from the C3D file format specification (c3d.org, "The
C3D File Format User Guide"), not from the project's reader: for checking that the files the
daemon writes read in another implementation. Intel (processor 84) files only, integer or
float storage, 3D points only (analog samples are skipped using the header's counts).

Prints one JSON object: points, frames, rate, labels, and the first and last frames' points
([x, y, z] or null for a missing sample: a negative residual).

  c3d_spec_reader.py FILE
"""
import json
import struct
import sys


def read(path):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 512 or data[1] != 0x50:
        raise ValueError("not a C3D file (header key byte is not 0x50)")
    parameter_block = data[0]
    # Header words (16-bit, 1-based in the specification): 2 points, 3 analog words per frame,
    # 4 first frame, 5 last frame, 7-8 scale (float), 9 data start block, 11-12 frame rate.
    points, analog_words, first, last = struct.unpack_from("<HHHH", data, 2)
    scale = struct.unpack_from("<f", data, 12)[0]
    data_start = struct.unpack_from("<H", data, 16)[0]
    rate = struct.unpack_from("<f", data, 20)[0]

    start = (parameter_block - 1) * 512
    blocks, processor = data[start + 2], data[start + 3]
    if processor != 84:
        raise ValueError("processor %d: this reader reads Intel files only" % processor)
    groups, params = {}, {}
    at, end = start + 4, start + blocks * 512
    while at < end:
        name_length = struct.unpack_from("<b", data, at)[0]
        if name_length == 0:
            break
        group_id = struct.unpack_from("<b", data, at + 1)[0]
        name = data[at + 2:at + 2 + abs(name_length)].decode("ascii", "replace").upper()
        link_at = at + 2 + abs(name_length)
        link = struct.unpack_from("<h", data, link_at)[0]
        body = link_at + 2
        if group_id < 0:
            groups[-group_id] = name
        else:
            kind = struct.unpack_from("<b", data, body)[0]
            dims = list(data[body + 2:body + 2 + data[body + 1]])
            values_at = body + 2 + len(dims)
            count = 1
            for d in dims:
                count *= d
            size = abs(kind) * count
            raw = data[values_at:values_at + size]
            if kind == -1:
                width = dims[0] if dims else 1
                value = [raw[i:i + width].decode("ascii", "replace").rstrip() for i in range(0, len(raw), width)] if dims else raw.decode()
            elif kind == 2:
                value = list(struct.unpack("<%dh" % count, raw))
            elif kind == 4:
                value = list(struct.unpack("<%df" % count, raw))
            else:
                value = list(raw)
            params[(group_id, name)] = value
        if link == 0:
            break
        at = link_at + link

    def param(group, name):
        for gid, gname in groups.items():
            if gname == group and (gid, name) in params:
                return params[(gid, name)]
        return None

    used = param("POINT", "USED")
    if used is not None:
        points = used[0] & 0xFFFF
    frames = last - first + 1
    point_frames = param("POINT", "FRAMES")
    if point_frames is not None:
        frames = point_frames[0] & 0xFFFF
    start_field, end_field = param("TRIAL", "ACTUAL_START_FIELD"), param("TRIAL", "ACTUAL_END_FIELD")
    if start_field and end_field:  # two 16-bit words each: low, high
        trial = (end_field[0] & 0xFFFF) + 65536 * (end_field[1] & 0xFFFF) - (start_field[0] & 0xFFFF) - 65536 * (start_field[1] & 0xFFFF) + 1
        if trial > 65535:
            frames = trial
    labels = []
    for suffix in ["", "2", "3", "4", "5"]:
        more = param("POINT", "LABELS" + suffix)
        if more is None:
            break
        labels += more
    labels = labels[:points]
    p_scale = param("POINT", "SCALE")
    if p_scale is not None:
        scale = p_scale[0]
    p_start = param("POINT", "DATA_START")
    if p_start is not None:
        data_start = p_start[0] & 0xFFFF

    float_storage = scale < 0
    word = 4 if float_storage else 2
    frame_bytes = (4 * points + analog_words) * word
    offset = (data_start - 1) * 512
    if offset + frames * frame_bytes > len(data):
        raise ValueError("truncated: %d frames of %d bytes do not fit in %d bytes" % (frames, frame_bytes, len(data)))

    def frame(i):
        out = []
        base = offset + i * frame_bytes
        for p in range(points):
            if float_storage:
                x, y, z, residual = struct.unpack_from("<ffff", data, base + 16 * p)
            else:
                x, y, z, residual = struct.unpack_from("<hhhh", data, base + 8 * p)
                x, y, z = x * scale, y * scale, z * scale
            out.append(None if residual < 0 else [x, y, z])
        return out

    return {
        "points": points,
        "frames": frames,
        "rate": rate,
        "labels": labels,
        "first": frame(0) if frames else None,
        "last": frame(frames - 1) if frames else None,
    }


if __name__ == "__main__":
    try:
        print(json.dumps(read(sys.argv[1])))
    except Exception as e:  # one line, a non-zero exit
        print("%s: %s" % (sys.argv[1], e), file=sys.stderr)
        sys.exit(1)
