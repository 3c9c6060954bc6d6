"""Before/after table of the fit with frames on the draws of this study
(`../compare_fit.py`).

Before: each draw's row in `quiet-noise-2026-12-04` (the 33 draws with shot noise in the
truth or the fit, binary de9f988), else in `before-extra.results.compact.jsonl` (the other
22, run here with the parent's behaviour: 19ee8b8, whose JSON is byte-identical to
d5f5824's). After: this study's `results.compact.jsonl`. Run from the repository root:
`python3 benches/coverage/quiet-noise-signature-2026-12-04/compare.py`.
"""
import runpy
import sys

HERE = 'benches/coverage/quiet-noise-signature-2026-12-04'
sys.argv = ['compare_fit.py', f'{HERE}/results.compact.jsonl',
            f'{HERE}/before-extra.results.compact.jsonl',
            'benches/coverage/quiet-noise-2026-12-04/results.compact.jsonl']
runpy.run_path('benches/coverage/compare_fit.py', run_name='__main__')
