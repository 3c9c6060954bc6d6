#!/usr/bin/env python3
"""Times v2e's own emulation loop (EventEmulator.generate_events, PyTorch on the CPU) on
frames written by `examples/simulator_throughput.rs` (FRAMES_NPY=...), for the side-by-side
figure of benches/README.md. v2e itself is not part of ctcal: point V2E_DIR at a checkout
of github.com/SensorsINI/v2e. Modules v2e imports only for its GUI, video input or
progress printing (cv2, screeninfo, easygui, numba, engineering_notation,
dv_processing) are stubbed.

usage: V2E_DIR=... v2e_loop.py FRAMES.npy MODEL [TORCH_THREADS]
  MODEL: ideal (thresholds 0.3, nothing else) or all_effects (calib/params/all_effects.toml
  in v2e's terms: 0.35/0.45, sigma 0.03, 300 Hz, 0.1 Hz leak, 1 Hz shot noise, 0.5 ms
  refractory period). Prints one JSON line: frames, seconds, frames/s, events.
"""
import json
import os
import sys
import time
import types

import numpy as np


def stub_modules():
    """Empty stand-ins for imports the emulation loop never calls."""
    for name in ("cv2", "screeninfo", "easygui", "engineering_notation", "numba",
                 "dv_processing"):
        module = types.ModuleType(name)
        sys.modules[name] = module
    sys.modules["screeninfo"].get_monitors = lambda: []
    sys.modules["engineering_notation"].EngNumber = lambda x, *a, **k: x
    sys.modules["numba"].njit = lambda *a, **k: (a[0] if a and callable(a[0]) else (lambda f: f))


MODELS = {
    "ideal": dict(pos_thres=0.3, neg_thres=0.3, sigma_thres=0.0, cutoff_hz=0.0,
                  leak_rate_hz=0.0, refractory_period_s=0.0, shot_noise_rate_hz=0.0),
    "all_effects": dict(pos_thres=0.35, neg_thres=0.45, sigma_thres=0.03, cutoff_hz=300.0,
                        leak_rate_hz=0.1, refractory_period_s=0.0005,
                        shot_noise_rate_hz=1.0),
}


def main():
    frames_path, model = sys.argv[1], sys.argv[2]
    threads = int(sys.argv[3]) if len(sys.argv) > 3 else 1
    stub_modules()
    sys.path.insert(0, os.environ["V2E_DIR"])
    import torch

    torch.set_num_threads(threads)
    from v2ecore.emulator import EventEmulator

    data = np.load(frames_path)  # (N, H, W) float32 DN, 1 kHz
    emulator = EventEmulator(device="cpu", seed=1, **MODELS[model])
    emulator.generate_events(data[0], 0.0)  # the first frame only initialises
    events = 0
    started = time.perf_counter()
    for k in range(1, data.shape[0]):
        out = emulator.generate_events(data[k], k / 1000.0)
        if out is not None:
            events += len(out)
    seconds = time.perf_counter() - started
    steps = data.shape[0] - 1
    print(json.dumps({"model": model, "torch_threads": threads, "frames": steps,
                      "seconds": seconds, "frames_per_s": steps / seconds, "events": events}))


if __name__ == "__main__":
    main()
