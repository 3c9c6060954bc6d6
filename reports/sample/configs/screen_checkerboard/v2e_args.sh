#!/bin/sh
# v2e with the parameters ctcal fitted to a recording. Run it as it is, with v2e's
# input and output arguments after it:
#   sh v2e_args.sh -i video.mp4 --output_folder out
# (V2E=/path/to/v2e.py sh v2e_args.sh ... runs another v2e.)
# NOT IDENTIFIED: ct_sigma: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (per-pixel threshold mismatch shows in how many events each pixel gives for the brightness change it saw: that needs grey frames or a known stimulus (estimate screen))
# NOT IDENTIFIED: cutoff_hz: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (the photoreceptor bandwidth shows in how events lag brightness changes of known speed and intensity: that needs grey frames or a known stimulus)
# NOT IDENTIFIED: leak_rate_hz: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (the ON excess of isolated events, 0.00225 +- 0.00126 Hz, is not told apart from none: at most 0.00477 Hz (shot-noise events reset the pixel, so a leak much slower than the shot noise is hidden; and where the recording starts at a reset, a simulator's first frame or a camera's start, a leak whose period is longer than the time since fires no event yet: the bound holds for leak phases spread at random, as in a camera that has been running))
# NOT IDENTIFIED: refractory_s: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (no gap at the short end of the same-pixel intervals: a refractory period, if any, is at most 1 us where every event respects it (a camera's pixel resets at each; v2e and ctcal's simulator let shot-noise events through it))
# NOT IDENTIFIED: shot_noise_rate_hz: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (not told apart from none: at most 0.00225 Hz (2 standard errors))
# NOT IDENTIFIED: timestamp_jitter_s: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (timestamp jitter shows against a stimulus of known timing: that needs a screen recording or frames)
# NOT DETECTED: hot_pixel_fraction: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: hot_pixels not kept: the fit blocks do not call for it; the hot-pixel search would name a pixel whose train fires 316 Hz or faster beyond its scene at 95 % or more of the kept pixels (hot_pixel_detection, on this recording's counts: the search's test alone, which the fit's later checks can only lower), so a hot pixel that fast would likely have been named; slower ones hide among the scene's events
# NOT DETECTED: hot_pixel_rate_hz: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: hot_pixels not kept: the fit blocks do not call for it; the hot-pixel search would name a pixel whose train fires 316 Hz or faster beyond its scene at 95 % or more of the kept pixels (hot_pixel_detection, on this recording's counts: the search's test alone, which the fit's later checks can only lower), so a hot pixel that fast would likely have been named; slower ones hide among the scene's events
exec "${V2E:-v2e}" \
  --pos_thres 0.325233 \
  --neg_thres 0.323379 \
  --sigma_thres 0 \
  --cutoff_hz 0 \
  --leak_rate_hz 0 \
  --shot_noise_rate_hz 0 \
  --refractory_period 0 \
  --leak_jitter_fraction 0.100000 \
  --noise_rate_cov_decades 0.100000 \
  --dvs_emulator_seed 2020 \
  --output_width 120 \
  --output_height 90 \
  "$@"
