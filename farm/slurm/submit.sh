#!/usr/bin/env bash
# Submits an indra render to Slurm as three jobs: a bake that writes checkpoints every
# --per-task frames, an array of render tasks (one contiguous chunk each, started from the
# checkpoint at its first frame) that waits for the bake, and an assemble that waits for all of
# them. Prints the three job ids.
#
#   farm/slurm/submit.sh SCENE OUTDIR [--frames A-B] [--per-task N] [--size WxH] [--fps F]
#                        [--video NAME] [--indra PATH] [--wait] [-- SBATCH-OPTIONS…]
#
# --wait returns when the assemble job ends, with its exit status. Options after -- go to every
# sbatch (a partition, an account, a GPU request: --gres=gpu:1). See docs/farm.md.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
[ $# -ge 2 ] || { sed -n 2,12p "$0" >&2; exit 2; }
scene=$1 out=$2
shift 2
frames=0-599 per_task=100 size=1920x1080 fps=60 video=render.mov indra=indra wait=()
while [ $# -gt 0 ]; do
  case $1 in
    --frames) frames=$2; shift 2 ;;
    --per-task) per_task=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --fps) fps=$2; shift 2 ;;
    --video) video=$2; shift 2 ;;
    --indra) indra=$2; shift 2 ;;
    --wait) wait=(--wait); shift ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
first=${frames%-*} last=${frames#*-}
if ! [[ $first =~ ^[0-9]+$ && $last =~ ^[0-9]+$ && $per_task =~ ^[1-9][0-9]*$ ]] || (( first > last )); then
  echo "submit.sh: --frames must be A-B with A <= B, --per-task a positive number" >&2
  exit 2
fi
tasks=$(( (last - first) / per_task + 1 ))
mkdir -p "$out/logs"
export INDRA="$indra" INDRA_SCENE="$scene" INDRA_OUT="$(cd "$out" && pwd)" INDRA_SIZE="$size" \
  INDRA_FIRST="$first" INDRA_LAST="$last" INDRA_PER_TASK="$per_task" INDRA_FPS="$fps" INDRA_VIDEO="$video"
logs=(--output "$INDRA_OUT/logs/%x-%j.out")
bake=$(sbatch --parsable --export=ALL "${logs[@]}" "$@" "$here/bake.sbatch")
render=$(sbatch --parsable --export=ALL --dependency="afterok:$bake" --array="0-$((tasks - 1))" \
  --output "$INDRA_OUT/logs/%x-%A_%a.out" "$@" "$here/render.sbatch")
echo "bake $bake"
echo "render $render ($tasks tasks)"
assemble=$(sbatch --parsable --export=ALL --dependency="afterok:$render" "${logs[@]}" "${wait[@]}" "$@" \
  "$here/assemble.sbatch")
echo "assemble ${assemble%%;*}"
