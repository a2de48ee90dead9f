"""Render a contact, localise it, and show the images.

    pip install ./python matplotlib
    python python/examples/render_and_localise.py [--object cone] [--at rotation=45] \
        [--azimuth 30] [--depth 1.0] [--save contact.png]

Prints the labels' contact centre, the localiser's estimate and the error; then shows the
reference, the contact and its indentation map with matplotlib (or saves them with --save).
"""
import argparse
import os

import numpy as np

import geltip


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sensor", default="paper")
    ap.add_argument("--object", default="sphere")
    ap.add_argument("--at", default="rotation=45")
    ap.add_argument("--azimuth", type=float, default=30.0)
    ap.add_argument("--depth", type=float, default=1.0)
    ap.add_argument("--method", default="surface", choices=["surface", "paper"])
    ap.add_argument("--save", help="write the figure here instead of showing it")
    args = ap.parse_args()
    os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")

    sensor = geltip.Sensor(args.sensor)
    sim = geltip.Simulator(sensor)
    reference = sim.reference()
    image, labels, depth = sim.render(object=args.object, at=args.at, azimuth=args.azimuth,
                                      depth=args.depth)
    found = geltip.localise(sensor, reference, image, method=args.method)

    truth = np.array(labels["contact_centre"])
    print(f"rendered on {sim.host}")
    print(f"{args.object} at {args.at}, azimuth {args.azimuth} deg, {args.depth} mm deep: "
          f"contact centre {np.round(truth, 3).tolist()} mm, {labels['mask_pixels']} pixels pressed")
    if found["detected"]:
        error = np.linalg.norm(np.array(found["point"]) - truth)
        print(f"{args.method} detector: pixel {np.round(found['pixel'], 1).tolist()}, point "
              f"{np.round(found['point'], 3).tolist()} mm, error {error:.3f} mm")
    else:
        print(f"{args.method} detector: nothing found ({found['note']})")

    try:
        import matplotlib

        if args.save:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: pip install matplotlib to see the images")
        return
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    ax[0].imshow(reference)
    ax[0].set_title("reference")
    ax[1].imshow(image)
    ax[1].set_title(f"{args.object}, {args.at}")
    if found["detected"] and found["pixel"] is not None:
        ax[1].plot(*found["pixel"], "w+", markersize=14, label=f"{args.method} detector")
        ax[1].legend(loc="lower right")
    shown = ax[2].imshow(depth, cmap="magma")
    ax[2].set_title("indentation (mm)")
    fig.colorbar(shown, ax=ax[2])
    for a in ax:
        a.axis("off")
    fig.tight_layout()
    if args.save:
        fig.savefig(args.save, dpi=80)
        print(f"wrote {args.save}")
    else:
        plt.show()


if __name__ == "__main__":
    main()
