#!/bin/bash
# The three sets of draws, eppps only, with one binary: run once with the binary before
# (4e872e5) and once after (6de153c); compare with compare.py BEFORE AFTER.
# usage: run.sh CTCAL OUT
bin=$1; out=$2
cov=target/release/examples/coverage
$cov --cases 40 --seed 11001 --generators ctcal,esim,voltmeter,iebcs --methods eppps --jobs 2 --threads 1 --out $out/11k --ctcal $bin
$cov --cases 40 --seed 12001 --generators ctcal,esim,voltmeter,iebcs --methods eppps --jobs 2 --threads 1 --out $out/12k --ctcal $bin
$cov --cases 80 --seed 2001 --methods eppps --jobs 2 --threads 1 --out $out/2k --ctcal $bin
cat $out/{11k,12k,2k}/results.compact.jsonl > $out/results.compact.jsonl
