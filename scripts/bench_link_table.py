#!/usr/bin/env python3
"""The shaped-link table: skinstream-bench for each encoding x subscriber count x link rate.

Runs the real daemon behind a veth pair shaped by tc (skinstream-bench --link-mbit; needs root
and iproute2), one run per cell, and prints one JSON object per run (the figures the table
quotes) and then the markdown table. Usage:

  scripts/bench_link_table.py BUILD_DIR [--seconds 10] [--encodings parameters,compressed]
                              [--subscribers 1,4,16,64] [--links 1000,100]
"""
import argparse
import json
import subprocess
import sys


def run_cell(bench, demo, encoding, subscribers, link, seconds):
    command = [bench, "--subject", f"{demo}/subject.sksubj", "--recording", f"{demo}/live.c3d", "--seconds", str(seconds),
               "--subscribers", str(subscribers), "--encoding", encoding, "--link-mbit", str(link), "--json"]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        return {"encoding": encoding, "subscribers": subscribers, "link_mbit": link, "error": done.stderr.strip().splitlines()[-1:]}
    r = json.loads(done.stdout)
    frames = r["frames"]
    return {
        "encoding": encoding, "subscribers": subscribers, "link_mbit": link,
        "slowest_fps": round(r["subscriber_frames_per_second"]["slowest"], 1),
        "end_to_end_p99_ms": round(r["end_to_end"]["p99_ms"], 2),
        "processing_p99_ms": round(r["daemon_processing"]["p99_ms"], 2),
        "bytes_per_frame": round(r["bytes_per_frame"]),
        "daemon_cpu_share": round(r["daemon"]["cpu_share_of_one_core"], 2),
        "dropped_for_subscribers": frames["dropped_for_subscribers"],
        "dropped_in_pipeline": frames["dropped_in_pipeline"],
        "model_bytes": r["model_bytes"],
        "command": " ".join(command),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build")
    parser.add_argument("--seconds", type=float, default=10)
    parser.add_argument("--encodings", default="parameters,compressed,quantised,float")
    parser.add_argument("--subscribers", default="1,4,16,64")
    parser.add_argument("--links", default="1000,100")
    a = parser.parse_args()
    bench, demo = f"{a.build}/bin/skinstream-bench", f"{a.build}/demo"
    rows = []
    for link in [int(x) for x in a.links.split(",")]:
        for encoding in a.encodings.split(","):
            for subscribers in [int(x) for x in a.subscribers.split(",")]:
                row = run_cell(bench, demo, encoding, subscribers, link, a.seconds)
                print(json.dumps(row), flush=True)
                rows.append(row)
    print("\n| link | encoding | subscribers | slowest frames/s | p99 end to end | bytes/frame | daemon CPU | dropped |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        if "error" in r:
            print(f"| {r['link_mbit']} | {r['encoding']} | {r['subscribers']} | error: {r['error']} | | | | |")
            continue
        print(f"| {r['link_mbit']} Mbit/s | {r['encoding']} | {r['subscribers']} | {r['slowest_fps']} | {r['end_to_end_p99_ms']} ms | "
              f"{r['bytes_per_frame']:,} | {round(100 * r['daemon_cpu_share'])}% | {r['dropped_for_subscribers']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
