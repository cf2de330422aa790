#!/bin/sh
# Regenerates {robot_net,ori_boost_net,ori_net}.weights (into perception/models unless told) from the training
# scenarios in scenes/train (never the evaluation scenes). Deterministic: same code, same
# weights. Usage: scripts/train_robot_nets.sh [build dir] [work dir] [models dir]
set -eu
BUILD=${1:-build}
WORK=${2:-/tmp/colorfree_robot_nets}
CF="$BUILD/bin/colorfree"
MODELS=${3:-perception/models}
rm -rf "$WORK"
"$CF" robot-data scenes/train/robot_detect_train.yaml scenes/train/robot_orientation_train.yaml \
  --out "$WORK" --seed 11
"$CF" train --cfg perception/models/robot_net.cfg --data "$WORK/robot_net" --classes none,robot \
  --out "$MODELS"/robot_net.weights --epochs 40 --patience 10 --seed 1 --quiet
"$CF" train --cfg perception/models/ori_boost_net.cfg --data "$WORK/ori_boost_net" \
  --classes unusable,usable --out "$MODELS"/ori_boost_net.weights --epochs 60 --patience 15 \
  --seed 1 --quiet
"$CF" train --cfg perception/models/ori_net.cfg --data "$WORK/ori_net" --classes front,back,side \
  --out "$MODELS"/ori_net.weights --epochs 60 --patience 15 --seed 1 --quiet
