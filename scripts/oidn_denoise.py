#!/usr/bin/env python3
"""Runs Intel Open Image Denoise's `RT` filter (the pinned pyoidn wheel, scripts/install_oidn.sh)
on raw images, for penumbra's comparison test (tests/denoise.rs) and `penumbra bench denoise`.

    oidn_denoise.py W H QUALITY DEVICE COLOR ALBEDO NORMAL OUT [RUNS]

COLOR, ALBEDO and NORMAL are raw little-endian f32 RGB images, row-major, H x W x 3; the filter
runs with hdr=true and the three inputs (OIDN's rt_hdr_alb_nrm weights), QUALITY `high` or
`fast` (the small weights), on DEVICE `cpu` or `cuda`, and writes OUT in the same form.
QUALITY `large` first filters the albedo and the normal on their own (quality `balanced`: the
rt_alb and rt_nrm weights), then the colour with those and cleanAux=true at quality `high`
(rt_hdr_calb_cnrm_large); with RUNS > 0 only that last filter is timed. With
RUNS > 0 it then executes the committed filter RUNS more times and prints one JSON line,
{"ms": [...]}: the wall time of each execution (the first, the build's, is not among them).
"""

import json
import sys
import time

import numpy as np
import pyoidn


def main():
    w, h, quality, device_name = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4]
    color, albedo, normal, out = sys.argv[5:9]
    runs = int(sys.argv[9]) if len(sys.argv) > 9 else 0
    load = lambda path: np.ascontiguousarray(np.fromfile(path, dtype="<f4").reshape(h, w, 3))
    images = {
        pyoidn.OIDN_IMAGE_COLOR: load(color),
        pyoidn.OIDN_IMAGE_ALBEDO: load(albedo),
        pyoidn.OIDN_IMAGE_NORMAL: load(normal),
    }
    output = np.zeros((h, w, 3), dtype=np.float32)
    kind = {"cpu": pyoidn.OIDN_DEVICE_TYPE_CPU, "cuda": pyoidn.OIDN_DEVICE_TYPE_CUDA}[device_name]
    device = pyoidn.Device(kind)
    device.commit()
    clean = quality == "large"
    if clean:
        for name in (pyoidn.OIDN_IMAGE_ALBEDO, pyoidn.OIDN_IMAGE_NORMAL):
            guide = images[name]
            prefilter = pyoidn.Filter(device, pyoidn.OIDN_FILTER_TYPE_RT)
            prefilter.set_image(name, guide, pyoidn.OIDN_FORMAT_FLOAT3)
            prefilter.set_image(pyoidn.OIDN_IMAGE_OUTPUT, guide, pyoidn.OIDN_FORMAT_FLOAT3)
            prefilter.set_quality(pyoidn.OIDN_QUALITY_BALANCED)
            prefilter.commit()
            prefilter.execute()
    flt = pyoidn.Filter(device, pyoidn.OIDN_FILTER_TYPE_RT)
    for name, image in images.items():
        flt.set_image(name, image, pyoidn.OIDN_FORMAT_FLOAT3)
    flt.set_image(pyoidn.OIDN_IMAGE_OUTPUT, output, pyoidn.OIDN_FORMAT_FLOAT3)
    flt.set_bool("hdr", True)
    flt.set_bool("cleanAux", clean)
    flt.set_quality(
        {"high": pyoidn.OIDN_QUALITY_HIGH, "large": pyoidn.OIDN_QUALITY_HIGH,
         "fast": pyoidn.OIDN_QUALITY_FAST}[quality]
    )
    flt.commit()
    flt.execute()
    error = device.get_error()
    if error:
        sys.exit(f"oidn_denoise: {error}")
    output.astype("<f4").tofile(out)
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        flt.execute()
        times.append((time.perf_counter() - start) * 1e3)
    if runs:
        print(json.dumps({"ms": times}))


if __name__ == "__main__":
    main()
