#!/usr/bin/env bash
# Runs a sharded campaign on Kubernetes: the Indexed Job of shards, then (once it is complete)
# the merge Job. Kubernetes has no dependency between Jobs, so this waits in between.
#   deploy/k8s/run.sh [TIMEOUT, default 24h]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
timeout=${1:-24h}
kubectl apply -f "$here/campaign-shards.yaml"
kubectl wait --for=condition=complete --timeout="$timeout" job/vmc-campaign-shards
kubectl apply -f "$here/merge-job.yaml"
kubectl wait --for=condition=complete --timeout=1h job/vmc-campaign-merge
echo "merged: /results/merged/report.json, summary: /results/summary.txt on the results volume"
