"""The quiet share (`events_only.quiet_share`) that Poisson noise alone leaves, simulated.

A pixel is uncovered where none of its N neighbours has an event within +-W; it counts as
quiet when uncovered at least half of a block (`QUIET_SHARE`), and the share is the quiet
pixels' uncovered time over all pixel time. N = 8 (3 x 3), W = 10 ms, blocks of 0.1 s and
1 s, noise of r Hz a pixel (ON + OFF). Usage: python3 quiet_share_noise.py (numpy).
"""
import numpy as np

rng = np.random.default_rng(1)
W, N = 0.01, 8
for block in (0.1, 1.0):
    cells = []
    for r in (2, 4.3, 5, 6, 7, 8, 10, 14):
        shares = []
        for _ in range(4000):
            t = np.sort(rng.uniform(-W, block + W, rng.poisson(N * r * (block + 2 * W))))
            covered, end = 0.0, 0.0
            for x in t:
                lo, hi = max(x - W, 0.0, end), min(x + W, block)
                if hi > lo:
                    covered += hi - lo
                end = max(end, min(x + W, block))
            u = (block - covered) / block
            shares.append(u if u >= 0.5 else 0.0)
        cells.append(f"{r:g} Hz: {np.mean(shares):.3f}")
    print(f"block {block:.1f} s:", ", ".join(cells))
