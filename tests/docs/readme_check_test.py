#!/usr/bin/env python3
"""readme_check.py itself: each rule fails on a README that breaks it, and passes a good one."""
import os
import subprocess
import sys
import tempfile

CHECK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "readme_check.py")


def run(text):
    with tempfile.TemporaryDirectory() as folder:
        os.makedirs(os.path.join(folder, "docs"))
        open(os.path.join(folder, "docs", "exists.md"), "w").close()
        path = os.path.join(folder, "README.md")
        with open(path, "w") as f:
            f.write(text)
        done = subprocess.run([sys.executable, CHECK, path], capture_output=True, text=True)
        return done.returncode, done.stdout


def main():
    good = "# x\n\nSee [the log](docs/exists.md).\n\n## Current figures\n\n| what | at |\n|---|---|\n| p99 1 ms | 1a2b3c4 |\n"
    failures = []
    code, out = run(good)
    if code != 0:
        failures.append("a good README failed: " + out)
    code, out = run(good + "x\n" * 300)
    if code == 0 or "more than 300" not in out:
        failures.append("301+ lines passed")
    code, out = run("Measured at 1a2b3c4 yesterday.\n" + good)
    if code == 0 or "commit hash 1a2b3c4" not in out:
        failures.append("a hash in prose passed")
    code, out = run(good.replace("docs/exists.md", "docs/gone.md"))
    if code == 0 or "docs/gone.md" not in out:
        failures.append("a broken link passed")
    code, out = run("The word facade and 1234567 are no hashes.\n" + good)
    if code != 0:
        failures.append("a word of letters or digits only was taken for a hash: " + out)
    for f in failures:
        print(f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
