#!/usr/bin/env python3
"""Measures how the memory and time of `vmc-twin merge` grow with the size of a fleet.

Running a 1,000-machine campaign to measure the merge would take hours, and the merge's cost
depends only on how many runs it streams, not on their values. So this script takes the shard
folders of a real sharded campaign (all shards of one split) and writes, for each fleet size
asked, a shard set of that many machines whose results are the real machines' results repeated
under new seed numbers (seed k holds the results of real machine (k-1) mod n + 1, with its
trained models). It then merges each set with `/usr/bin/time` and prints the peak memory and
wall time against the number of machines and runs.

The synthetic shard sets are for this measurement only: their figures repeat the real machines
and say nothing about a fleet of that size.

Usage:
    campaign --seeds 1..26 --shard 1/2 --out s1; ... --shard 2/2 --out s2
    scripts/merge-memory.py VMC_TWIN_BINARY WORK_DIR s1 s2 --machines 26 200 1000
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys


def read_shards(dirs):
    """The real machines' result lines (in seed order) and model files, and a manifest."""
    manifests = [json.load(open(os.path.join(d, "shard.json"))) for d in dirs]
    manifests_dirs = sorted(zip(manifests, dirs), key=lambda md: md[0]["shard"]["index"])
    lines, models = [], []
    for m, d in manifests_dirs:
        with open(os.path.join(d, "seeds.jsonl")) as f:
            for line in f:
                seed = json.loads(line)["seed"]
                lines.append((seed, line))
                models.append(
                    {
                        kind: os.path.join(d, f"model_{kind}_seed{seed}.json")
                        for kind in ("hybrid", "volumetric", "linear")
                    }
                )
    return manifests_dirs[0][0], lines, models


SEED_FIELD = re.compile(r'"seed":(\d+)')
TRAINING_SEED = re.compile(r'"training":\[\[(\d+),')


def renumber(line, old, new):
    """A result line of machine `old` as machine `new` (its seed fields and training pairs)."""
    line = SEED_FIELD.sub(lambda m: f'"seed":{new}' if int(m.group(1)) == old else m.group(0), line)
    return line.replace(f"[{old},{{", f"[{new},{{")


def write_fleet(out, manifest, lines, models, machines, shards=2):
    """A shard set of `machines` machines in `shards` shards under `out`."""
    if os.path.exists(out):
        shutil.rmtree(out)
    dirs = []
    for i in range(1, shards + 1):
        lo, hi = (i - 1) * machines // shards, i * machines // shards
        d = os.path.join(out, f"s{i}")
        os.makedirs(d)
        with open(os.path.join(d, "seeds.jsonl"), "w") as f:
            for seed in range(lo + 1, hi + 1):
                k = (seed - 1) % len(lines)
                old, line = lines[k]
                f.write(renumber(line, old, seed))
                for kind, path in models[k].items():
                    os.link(path, os.path.join(d, f"model_{kind}_seed{seed}.json"))
        m = dict(manifest)
        m["shard"] = {"index": i, "count": shards}
        m["work_ids"] = [f"seed {s}" for s in range(lo + 1, hi + 1)]
        m["work_total"] = machines
        m["inputs"] = [
            dict(x, fnv1a64=f"{machines:016x}") if x["name"] == "seeds" else x
            for x in manifest["inputs"]
        ]
        with open(os.path.join(d, "shard.json"), "w") as f:
            json.dump(m, f, indent=2)
        dirs.append(d)
    return dirs


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("binary")
    p.add_argument("work_dir")
    p.add_argument("shard_dirs", nargs="+")
    p.add_argument("--machines", type=int, nargs="+", required=True)
    a = p.parse_args()
    manifest, lines, models = read_shards(a.shard_dirs)
    print(f"{'machines':>8} {'runs':>8} {'report.json MB':>15} {'peak MB':>8} {'wall s':>7}")
    for n in a.machines:
        base = os.path.join(a.work_dir, f"fleet{n}")
        dirs = write_fleet(base, manifest, lines, models, n)
        merged = os.path.join(base, "merged")
        r = subprocess.run(
            ["/usr/bin/time", "-f", "%M %e", a.binary, "merge", *dirs, "--out", merged],
            capture_output=True,
            text=True,
        )
        if r.returncode != 0:
            sys.exit(f"merge of {n} machines failed: {r.stderr}")
        peak_kb, wall_s = r.stderr.strip().splitlines()[-1].split()
        size_mb = os.path.getsize(os.path.join(merged, "report.json")) / 1e6
        runs = sum(1 for _ in open(os.path.join(merged, "report.json")) if '"predictor"' in _)
        print(f"{n:>8} {runs:>8} {size_mb:>15.0f} {int(peak_kb) / 1024:>8.1f} {float(wall_s):>7.2f}")
        shutil.rmtree(base)


if __name__ == "__main__":
    main()
