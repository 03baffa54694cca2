#!/usr/bin/env bash
# Submits a sharded campaign as a Slurm pipeline: a job array of N shards, then the merge,
# which starts only when every shard has succeeded (--dependency=afterok).
#
#   deploy/slurm/submit.sh OUT N CPUS_PER_TASK [campaign options, e.g. --seeds 1..1000]
#
# Prints the two job ids (array, merge). Results: OUT/merged/report.json and OUT/summary.txt;
# logs: OUT/logs/. Set VMC_TWIN to the program's path if it is not on the PATH of the nodes,
# and OUT to a folder every node sees.
#
#   VMC_COMMAND=select-sensors deploy/slurm/submit.sh OUT N CPUS [select-sensors options]
#
# shards select-sensors over its compare seeds instead; the merge writes OUT/merged/sensors.toml
# (the file name of -o) and, with --json, the JSON study; the report goes to OUT/summary.txt.
# VMC_COMMAND=lobes shards lobes over its speeds; the merge writes OUT/merged/lobes.csv (or the
# file name of --out) and the report to OUT/summary.txt.
# (sbatch passes the environment, VMC_COMMAND included, to both jobs.)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
OUT=${1:?usage: submit.sh OUT N CPUS_PER_TASK [campaign options]}
N=${2:?number of shards}
CPUS=${3:?CPUs per array task}
shift 3
mkdir -p "$OUT/logs"
OUT=$(cd "$OUT" && pwd)
array=$(sbatch --parsable --array="1-$N" --cpus-per-task="$CPUS" \
  --output="$OUT/logs/shard-%a.out" --error="$OUT/logs/shard-%a.err" \
  "$here/campaign-shard.sbatch" "$OUT" "$N" "$@")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$OUT/logs/merge.out" --error="$OUT/logs/merge.err" \
  "$here/merge.sbatch" "$OUT" "$N")
echo "$array ${merge%%;*}"
