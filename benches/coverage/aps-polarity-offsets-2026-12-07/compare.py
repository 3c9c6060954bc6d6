# compare.py BEFORE AFTER: the shared comparison (`../compare_aps.py`) over the folders this
# study's draws were kept in (that session's paths).
import os
import subprocess
import sys

dirs = ['/work/s77/fresh15k-cases', '/work/s74/cases14k', '/work/s73/cases13k', '/work/s78/fresh16k/work']
shared = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'compare_aps.py')
sys.exit(subprocess.call([sys.executable, shared, *sys.argv[1:3], *dirs]))
