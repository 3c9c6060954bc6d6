"""Effects the fit added that the draw has (true) and does not have (false), per run.

python3 effects.py before/results.compact.jsonl after/results.compact.jsonl
"""
import json
import sys

PARAMETER = {
    "bandwidth": "cutoff_hz",
    "shot_noise": "shot_noise_rate_hz",
    "leak": "leak_rate_hz",
    "refractory": "refractory_s",
    "mismatch": "ct_sigma",
    "hot_pixels": "hot_pixel_fraction",
    "timestamp_jitter": "timestamp_jitter_s",
}

for path in sys.argv[1:]:
    true, false = [], []
    for line in open(path):
        run = json.loads(line)
        if run["outcome"].get("status") != "ok":
            continue
        params = run["case"]["params"]
        seed = run["case"]["seed"]
        for effect in run.get("effects_added") or []:
            (true if params.get(PARAMETER[effect]) else false).append(f"{seed} {effect}")
    print(f"{path}: {len(true)} true, {len(false)} false")
    print("  false:", ", ".join(false) or "none")
    print("  true:", ", ".join(true))
