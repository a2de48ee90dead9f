"""Load a set made by `geltip dataset` with numpy + Pillow, and as a PyTorch Dataset.

    python3 examples/load_dataset.py data/train

Prints a summary and checks each sample (image size, mask against its label).
"""
import json
import sys
from pathlib import Path

import numpy as np
from PIL import Image


def load_labels(root):
    """The labels, one dict per sample, sorted by index."""
    root = Path(root)
    with open(root / "labels.jsonl") as f:
        return [json.loads(line) for line in f if line.strip()]


def load_sample(root, label):
    """(image HxWx3 uint8, depth HxW float32 mm or None, mask HxW bool or None)."""
    root = Path(root)
    image = np.asarray(Image.open(root / label["image"]).convert("RGB"))
    depth = np.load(root / label["depth"]) if label.get("depth") else None
    mask = np.asarray(Image.open(root / label["mask"])) > 127 if label.get("mask") else None
    return image, depth, mask


try:
    import torch
    from torch.utils.data import Dataset

    class GelTipDataset(Dataset):
        """Images as float CxHxW in [0, 1]; target: contact pixel (u, v), 3D point (mm),
        press depth (mm) and, when the set has them, the mask and depth map."""

        def __init__(self, root):
            self.root = Path(root)
            self.labels = load_labels(self.root)

        def __len__(self):
            return len(self.labels)

        def __getitem__(self, i):
            label = self.labels[i]
            image, depth, mask = load_sample(self.root, label)
            x = torch.from_numpy(image).permute(2, 0, 1).float() / 255.0
            target = {
                "pixel": torch.tensor(label["pixel"] or [float("nan")] * 2),
                "point": torch.tensor(label["point"]),
                "depth_mm": torch.tensor(label["depth_mm"]),
            }
            if mask is not None:
                target["mask"] = torch.from_numpy(mask)
            if depth is not None:
                target["depth_map"] = torch.from_numpy(depth)
            return x, target

except ImportError:  # PyTorch is optional: the numpy loader above works without it
    GelTipDataset = None


def main(root):
    manifest = json.loads((Path(root) / "dataset.json").read_text())
    cfg = manifest["options"]["sensor_config"]["image"]
    labels = load_labels(root)
    assert [l["index"] for l in labels] == list(range(len(labels))), "labels not sorted"
    for label in labels:
        image, depth, mask = load_sample(root, label)
        assert image.shape == (cfg["height"], cfg["width"], 3), image.shape
        if mask is not None:
            assert int(mask.sum()) == label["mask_pixels"], (label["index"], int(mask.sum()))
            if label["pixel"] is not None and label["contact_indentation_mm"] > 0.05:
                u, v = (int(round(c)) for c in label["pixel"])
                assert mask[v, u], f"sample {label['index']}: pixel outside its mask"
        if depth is not None:
            assert depth.dtype == np.float32 and depth.shape == image.shape[:2]
            assert np.isfinite(depth).all()
    print(f"{len(labels)} samples of {cfg['width']}x{cfg['height']} from {root}: ok")
    if GelTipDataset is not None:
        x, target = GelTipDataset(root)[0]
        print("torch sample:", tuple(x.shape), sorted(target))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
