#!/bin/sh
# v2e with the parameters ctcal fitted to a recording. Run it as it is, with v2e's
# input and output arguments after it:
#   sh v2e_args.sh -i video.mp4 --output_folder out
# (V2E=/path/to/v2e.py sh v2e_args.sh ... runs another v2e.)
# NOT IDENTIFIED: ct_sigma: the value written (the simulator's default or off, or the start value the fit simulated) is not a measurement (the recording does not show a threshold spread: event timing on the fit run resolves no frozen threshold spread: its 95 % interval 0 to 0.0565 allows at most 0.0565 (such a limit held on 22 of 24 coverage draws with a spread) and the fit blocks have too few events per pixel to compare the counts' dispersion with the model's; the model has no mismatch, which is not a measurement)
# NOT DETECTED: cutoff_hz: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: bandwidth not kept: not called for by the residuals; a cutoff at white of 24.3 Hz or lower would have shown (in about 95 % of recordings of this scene: bandwidth_detection), so any cutoff is likely higher
# NOT DETECTED: hot_pixel_fraction: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: hot_pixels not kept: not called for by the residuals; the hot-pixel search would name a pixel whose train fires 100 Hz or faster beyond its scene at 95 % or more of the kept pixels (hot_pixel_detection, on this recording's counts: the search's test alone, which the fit's later checks can only lower), so a hot pixel that fast would likely have been named; slower ones hide among the scene's events
# NOT DETECTED: hot_pixel_rate_hz: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: hot_pixels not kept: not called for by the residuals; the hot-pixel search would name a pixel whose train fires 100 Hz or faster beyond its scene at 95 % or more of the kept pixels (hot_pixel_detection, on this recording's counts: the search's test alone, which the fit's later checks can only lower), so a hot pixel that fast would likely have been named; slower ones hide among the scene's events
# NOT DETECTED: leak_rate_hz: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: leak not kept: not called for by the residuals; its detection limit on this recording is 0.980 Hz (noise_detection: a rate at which the model's evidence calls for it), so a rate above that is unlikely; the event timing's drift allows at most 0.248 Hz at the frames' median DN (such a limit held on 51 of 54 coverage draws with a leak)
# NOT DETECTED: refractory_s: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: refractory not kept: not called for by the residuals; how strong it would have to be for this recording to show it was not measured
# NOT DETECTED: timestamp_jitter_s: written as off (zero, or the simulator's smallest value where it takes no zero), which is not a measurement of zero: timestamp_jitter not kept: not called for by the residuals; how strong it would have to be for this recording to show it was not measured
exec "${V2E:-v2e}" \
  --pos_thres 0.347131 \
  --neg_thres 0.473899 \
  --sigma_thres 0 \
  --cutoff_hz 0 \
  --leak_rate_hz 0 \
  --shot_noise_rate_hz 1.199974 \
  --refractory_period 0 \
  --leak_jitter_fraction 0.100000 \
  --noise_rate_cov_decades 0.100000 \
  --dvs_emulator_seed 2020 \
  --output_width 240 \
  --output_height 180 \
  "$@"
