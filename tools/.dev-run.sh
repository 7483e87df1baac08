#!/usr/bin/env bash
set -u
cd .device-carry && tar xJf bin.tar.xz && cd ..
export LD_LIBRARY_PATH=$PWD/.device-carry/lib
B=.device-carry/bin
R=$(mktemp -d); trap 'tar czf $OUT/run.tgz -C $R .' EXIT
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader > $R/gpu.txt; cat $R/gpu.txt; cat .device-carry/COMMIT
(timeout 240 $B/incision_gpu_tests --gtest_filter='-*Soak*' > $R/gpu_tests.txt 2>&1; echo "rc $?" >> $R/gpu_tests.txt)
tail -3 $R/gpu_tests.txt; grep -E "FAILED" $R/gpu_tests.txt | head
(time timeout 300 $B/incision tradeoff scenes/liver_grasp.json --models pbd --backend cuda --out $R/to_liver_cuda) > $R/to.txt 2>&1
tail -4 $R/to.txt
grep "^| pbd" $R/to_liver_cuda/tradeoff.md | sort -u
