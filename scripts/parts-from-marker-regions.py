#!/usr/bin/env python3
"""A technician's segmentation of a synthetic subject from its marker names, for
`skinstream eval-deform --part-file` (the README's hand-segmentation comparison).

Usage: parts-from-marker-regions.py NAMES.json OUT.json
NAMES.json: any {"marker name": ...} object naming every marker, e.g. what
`skinstream eval-deform --seed N --part-file-out NAMES.json` writes. The generator names
markers <region>[_L|_R]_<n>; regions are grouped into 12 parts: the upper trunk (chest,
upper back, scapulae, shoulders), the lower trunk (abdomen, lower back, pelvis), and per
side the buttock, thigh, lower leg (knee, shin, calf), upper arm and forearm (elbow, forearm).
"""
import json
import re
import sys

GROUPS = {
    "chest": "upper_trunk", "upperback": "upper_trunk", "scapula": "upper_trunk", "shoulder": "upper_trunk",
    "abdomen": "lower_trunk", "lowerback": "lower_trunk", "pelvis": "lower_trunk",
    "buttock": "buttock", "thigh": "thigh", "knee": "lower_leg", "shin": "lower_leg", "calf": "lower_leg",
    "upperarm": "upper_arm", "elbow": "forearm", "forearm": "forearm",
}


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    names = json.load(open(sys.argv[1]))
    ids, parts = {}, {}
    for name in names:
        m = re.fullmatch(r"([a-z]+)(_[LR])?_\d+", name)
        if not m or m.group(1) not in GROUPS:
            sys.exit(f"{sys.argv[1]}: marker {name!r} is not <region>[_L|_R]_<n> of a known region")
        group = GROUPS[m.group(1)]
        part = group if group.endswith("trunk") else group + (m.group(2) or "")
        parts[name] = ids.setdefault(part, len(ids))
    with open(sys.argv[2], "w") as out:
        json.dump(parts, out, indent=1)
    print(f"{len(ids)} parts: {', '.join(ids)}", file=sys.stderr)


if __name__ == "__main__":
    main()
