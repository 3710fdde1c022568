#!/usr/bin/python3
"""10^6 directions through the Python module against the C++ RadianceBatch, in one process.

    PYTHONPATH=build/python /usr/bin/python3 python/bench_sample.py [--count 1000000] [--repeat 5]

Times, best of --repeat, for one observer (altitude 0) and one sun (zenith 60 degrees), model
hillaire (preset earth, its sky-view table):
  - C++ RadianceBatch: SkyView::RadianceBatch (float32 radiance, no sun disc or ground) over the
    unit direction vectors, in chunks on oneTBB's threads as a frame uses it, timed inside C++
    (atmo._atmo.Model.time_radiance_batch), the view's tables made before the clock starts;
  - module radiance_batch: the same call through Python (directions in, float32 array out);
  - C++ sample loop: the computation behind Model.sample (EvaluateSample in python/bindings.cc)
    called from C++ on the same angles, without the Python layer;
  - module sample: Model.sample(0, 60, view_zenith, azimuth) from the angles, i.e. what `atmo
    sample` computes (double radiance, transmittance and standard error per point), including
    broadcasting, the directions' trigonometry and the view's tables.
The ratios to the C++ RadianceBatch are printed, and the module's sample against its C++ loop
(docs/python.md discusses the figures).
"""

import argparse
import os
import sys
import time

import numpy as np

# The source folder python/ holds the package's pure-Python half only: import the built package
# (PYTHONPATH), not python/atmo beside this script.
if sys.path and os.path.abspath(sys.path[0]) == os.path.dirname(os.path.abspath(__file__)):
    del sys.path[0]
import atmo  # noqa: E402


def best_of(repeat, function):
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--model", default="hillaire")
    parser.add_argument("--preset", default="earth")
    parser.add_argument("--spectral", type=int, default=0)
    args = parser.parse_args()

    model = atmo.Model(args.model, preset=args.preset, spectral=args.spectral)
    rng = np.random.default_rng(1)
    view_zenith = rng.uniform(0.0, 180.0, args.count)
    azimuth = rng.uniform(-180.0, 180.0, args.count)
    zr, ar = np.radians(view_zenith), np.radians(azimuth)
    directions = np.ascontiguousarray(np.stack([np.sin(zr) * np.sin(ar), np.sin(zr) * np.cos(ar), np.cos(zr)], -1))

    cpp = model._model.time_radiance_batch(0.0, 60.0, directions, args.repeat, True)
    cpp_serial = model._model.time_radiance_batch(0.0, 60.0, directions, max(1, args.repeat // 2), False)
    n = args.count
    cpp_sample = model._model.time_sample(np.zeros(n), np.full(n, 60.0), view_zenith, azimuth, args.repeat)
    batch = best_of(args.repeat, lambda: model.radiance_batch(0.0, 60.0, directions))
    sample = best_of(args.repeat, lambda: model.sample(0.0, 60.0, view_zenith, azimuth))
    sample32 = best_of(args.repeat, lambda: model.sample(0.0, 60.0, view_zenith, azimuth, dtype=np.float32))

    print(f"{args.count} directions, model {model.name}, preset {model.preset}, {model.channel_count} channels, "
          f"best of {args.repeat}")
    print(f"  C++ RadianceBatch (oneTBB chunks)      {cpp * 1e3:9.2f} ms")
    print(f"  C++ RadianceBatch (one thread)         {cpp_serial * 1e3:9.2f} ms")
    print(f"  module radiance_batch                  {batch * 1e3:9.2f} ms   {batch / cpp:5.2f} x C++")
    print(f"  C++ sample loop (EvaluateSample)       {cpp_sample * 1e3:9.2f} ms   {cpp_sample / cpp:5.2f} x C++")
    print(f"  module sample (float64)                {sample * 1e3:9.2f} ms   {sample / cpp:5.2f} x C++")
    print(f"  module sample (float32)                {sample32 * 1e3:9.2f} ms   {sample32 / cpp:5.2f} x C++")
    print(f"  module sample / C++ sample loop        {sample / cpp_sample:9.2f}")


if __name__ == "__main__":
    main()
