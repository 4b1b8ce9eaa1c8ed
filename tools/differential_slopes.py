"""What keeps the progressive error from falling, for the scenes tools/differential.py flagged for their slope.

Diagnostics only: the acceptance figure stays the runner's (docs/results/differential.md). For each flagged scene
of a results folder (its results/ and images/), the first of these that holds:

- pixels, Photon Splat's: the slope from 4 to 16 s is -0.3 or below once the 3 pixels furthest from Cycles at 16 s
  (relative to their block's mean) take Cycles' value in both snapshots, and one of them at least is brighter in
  Photon Splat where Cycles' two seeds agree within 10 %: a rare path's firefly in Photon Splat's image;
- pixels, Cycles' or dark: the same slope test holds, the pixels being otherwise (Cycles' pair apart there, or
  Photon Splat darker);
- Cycles' noisy blocks: the slope is -0.3 or below over the blocks whose Cycles pair agrees within 2 %;
- below the reference: Photon Splat's error at 16 s is already below the reference renderer's own (its pair at
  256 samples per seed or more), a floor no unbiased renderer at those samples would show either;
- multiscatter GGX glass: the scene holds one (docs/closures.md: photons cannot follow Cycles' walk numbers);
- unexplained.

    /usr/bin/python3 tools/differential_slopes.py build/differential
"""

import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from differential import BLOCK, SLOPE_MAX, block_means, block_relmse  # noqa: E402

WORST_PIXELS = 3


def slope(error_4, error_16):
    """Log-log slope of the error excess from 4 to 16 s; -inf where it is within Cycles' own noise at 16 s."""
    if error_16 <= 0:
        return -math.inf
    if error_4 <= 0:
        return math.inf
    return math.log(error_16 / error_4) / math.log(4)


def excess(image, cycles, spread, keep=None):
    raw, share = block_relmse(image, cycles, spread, keep)
    return raw - share


def classify(result, images):
    cycles, spread = images["cycles"], images["cycles_spread"]
    at_4, at_16 = images["ps_4"], images["ps_16"]
    luminance = lambda x: x[..., :3].mean(-1)  # noqa: E731
    lum_16, lum_cycles = luminance(at_16), luminance(cycles)
    block_mean = np.kron(luminance(block_means(cycles)), np.ones((BLOCK, BLOCK)))
    h, w = block_mean.shape
    off = np.abs(lum_16[:h, :w] - lum_cycles[:h, :w]) / np.maximum(block_mean, 1e-12)
    worst = np.unravel_index(np.argsort(off, axis=None)[::-1][:WORST_PIXELS], off.shape)
    patched_4, patched_16 = at_4.copy(), at_16.copy()
    patched_4[worst], patched_16[worst] = cycles[worst], cycles[worst]
    without_pixels = slope(excess(patched_4, cycles, spread), excess(patched_16, cycles, spread))
    photonsplat_bright = any(
        lum_16[p] > lum_cycles[p] and np.abs(spread[p][:3]).mean() < 0.1 * lum_cycles[p]
        for p in zip(*worst))
    blocks = luminance(block_means(cycles))
    blocks_spread = np.sqrt(luminance(block_means(np.square(spread))) / (BLOCK * BLOCK))
    quiet = blocks_spread / np.maximum(blocks, 1e-12) < 0.02
    keep = np.repeat(quiet[..., None], 3, axis=-1)
    quiet_slope = (slope(excess(at_4, cycles, spread, keep), excess(at_16, cycles, spread, keep))
                   if quiet.sum() >= 8 else math.nan)
    error_16 = result["photonsplat"]["times"]["16"]["relmse_excess"]
    if without_pixels <= SLOPE_MAX:
        kind = "pixels, Photon Splat's" if photonsplat_bright else "pixels, Cycles' or dark"
    elif quiet_slope <= SLOPE_MAX:
        kind = "Cycles' noisy blocks"
    elif error_16 < result["reference"]["relmse"]:
        kind = "below the reference"
    elif any("multiscatter GGX glass" in w for w in result["warnings"]):
        kind = "multiscatter GGX glass"
    else:
        kind = "unexplained"
    return kind, without_pixels, quiet_slope, int(quiet.sum()), error_16


def main(argv):
    out = Path(argv[0] if argv else "build/differential")
    counts = {}
    print("| seed | slope | without 3 pixels | over quiet blocks (count) | error at 16 s | reference's | kind |")
    print("|---|---|---|---|---|---|---|")
    for path in sorted(out.glob("results/*.json"), key=lambda p: int(p.stem)):
        result = json.loads(path.read_text())
        images_path = out / "images" / f"{result['seed']}.npz"
        if "slope" not in result["flags"] or not images_path.exists():
            continue
        kind, without_pixels, quiet_slope, quiet, error_16 = classify(result, dict(np.load(images_path)))
        counts[kind] = counts.get(kind, 0) + 1
        print(f"| {result['seed']} | {result['photonsplat']['slope']:.2f} | {without_pixels:.2f} | "
              f"{quiet_slope:.2f} ({quiet}) | {error_16:.1e} | {result['reference']['relmse']:.1e} | {kind} |")
    print()
    print(", ".join(f"{kind}: {n}" for kind, n in sorted(counts.items(), key=lambda kv: -kv[1])))


if __name__ == "__main__":
    main(sys.argv[1:])
