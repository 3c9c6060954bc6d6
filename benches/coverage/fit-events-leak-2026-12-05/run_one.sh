#!/bin/bash
c=$1; n=$(basename $c)
[ -e /work/s70/fe/$n.json ] && exit 0
timeout 900 /work/s70/fe/ctcal --threads 1 fit $c --no-frames --quiet --json /work/s70/fe/$n.json >/dev/null 2>/work/s70/fe/$n.err
