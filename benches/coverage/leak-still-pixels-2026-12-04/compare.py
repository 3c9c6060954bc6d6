"""Before/after table of the fit with frames on the 55 draws of
`../quiet-noise-signature-2026-12-04` (its seeds): before, the parent's binary
(`before.results.compact.jsonl`), after, this change's (`results.compact.jsonl`), both run
here on the same cases (`../compare_fit.py`). Run from the repository root:
`python3 benches/coverage/leak-still-pixels-2026-12-04/compare.py`.
"""
import runpy
import sys

sys.argv = ['compare_fit.py', 'benches/coverage/leak-still-pixels-2026-12-04/results.compact.jsonl', 'benches/coverage/leak-still-pixels-2026-12-04/before.results.compact.jsonl']
runpy.run_path('benches/coverage/compare_fit.py', run_name='__main__')
