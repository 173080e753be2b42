"""The output guide's error-layer picture (docs/src/output.md): a progressive render's beauty image beside its `error`
layer (the 95 % bound, noise + |bias|, over the pixel's grey value, 0–10 %), and beside the
actual error against a path-traced reference on the same scale.

    python3 benches/error-layer/picture.py RENDER.exr REFERENCE.exr OUT.png

Needs the Python packages OpenEXR, numpy and Pillow.
"""
import sys

import numpy as np
import OpenEXR
from PIL import Image, ImageDraw


def layer(path, name):
    with OpenEXR.File(path) as f:
        return f.channels()[name].pixels.astype(np.float64)


def srgb(v):
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def heat(x):
    """0 → dark blue, 0.5 → yellow, 1 → white-hot (a plain three-stop ramp)."""
    x = np.clip(x, 0.0, 1.0)[..., None]
    stops = np.array([[0.05, 0.05, 0.3], [0.9, 0.75, 0.1], [1.0, 1.0, 1.0]])
    lo = np.where(x < 0.5, stops[0], stops[1])
    hi = np.where(x < 0.5, stops[1], stops[2])
    t = np.where(x < 0.5, x * 2, x * 2 - 1)
    return lo + (hi - lo) * t


def main(render, reference, out):
    beauty = layer(render, "RGB")
    grey = beauty.mean(-1)
    bound = layer(render, "error")[..., 0]
    ref = layer(reference, "RGB").mean(-1)
    scale = 0.10
    rel = bound / np.maximum(grey, 1e-3)
    actual = np.abs(grey - ref) / np.maximum(grey, 1e-3)
    panels = [srgb(beauty), heat(rel / scale), heat(actual / scale)]
    h, w = grey.shape
    pad, label = 4, 18
    canvas = Image.new("RGB", (3 * w + 4 * pad, h + label + 2 * pad), (255, 255, 255))
    draw = ImageDraw.Draw(canvas)
    titles = ["image", "error layer (0-10 %)", "actual error (0-10 %)"]
    for i, (p, t) in enumerate(zip(panels, titles)):
        img = Image.fromarray((p * 255 + 0.5).astype(np.uint8))
        canvas.paste(img, (pad + i * (w + pad), label + pad))
        draw.text((pad + i * (w + pad) + 2, 3), t, fill=(0, 0, 0))
    canvas.save(out)
    lit = ref > 1e-3
    inside = (np.abs(grey - ref) <= bound)[lit].mean()
    print(f"{100 * inside:.1f} % of pixels within their bound; mean bound {rel[lit].mean():.4f}, "
          f"mean actual {actual[lit].mean():.4f} (relative to each pixel)")


if __name__ == "__main__":
    main(*sys.argv[1:4])
