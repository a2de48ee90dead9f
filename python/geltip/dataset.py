"""`geltip.Dataset`: a map-style dataset over a directory written by `geltip dataset`.

The directory holds `dataset.json` (the manifest), `labels.jsonl` (one JSON object per
sample), `images/<k>.png` and, when the set was made with `--depth-maps` / `--masks`,
`depth/<k>.npy` and `masks/<k>.png`. PNGs are read by geltip's own decoder (no Pillow).

With PyTorch installed, `Dataset` is a `torch.utils.data.Dataset` (use it with a
`DataLoader`: its default collate stacks the NumPy arrays into tensors); without it, a
plain `collections.abc.Sequence`.
"""
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Union

import numpy as np

try:  # PyTorch is optional
    from torch.utils.data import Dataset as _Base  # type: ignore[import-not-found]

    TORCH = True
except ImportError:  # pragma: no cover - depends on the environment
    _Base = Sequence  # type: ignore[misc,assignment]
    TORCH = False

Sample = Dict[str, Any]


class Dataset(_Base):  # type: ignore[misc,valid-type]
    """`Dataset(root)`: sample `i` is a dict with

    - ``index``: the sample's index in the set,
    - ``image``: (H, W, 3) uint8,
    - ``labels``: the sample's line of `labels.jsonl` (the ground truth of
      `geltip render --labels`, plus the sample's files, object and seed),
    - ``depth``: (H, W) float32 mm, when the set has depth maps,
    - ``mask``: (H, W) bool, when the set has masks,
    - ``reference``: (H, W, 3) uint8, the sample's own empty frame, when the set was put on
      a folder of backgrounds (`--background DIR`; else the set's is `reference.png`).

    ``transform``, if given, is applied to each sample dict.
    """

    def __init__(
        self,
        root: Union[str, "Path"],
        transform: Optional[Callable[[Sample], Any]] = None,
    ) -> None:
        self.root = Path(root)
        manifest = self.root / "dataset.json"
        self.manifest: Dict[str, Any] = (
            json.loads(manifest.read_text()) if manifest.is_file() else {}
        )
        # The library's reader: only an unfinished last line (a run killed while writing
        # it) is left out; any other bad line is an error naming it.
        from ._geltip import dataset_labels

        labels: List[Dict[str, Any]] = dataset_labels(self.root)
        labels.sort(key=lambda label: label["index"])
        self.labels = labels
        self.transform = transform

    def __len__(self) -> int:
        return len(self.labels)

    def __getitem__(self, i: int) -> Any:  # type: ignore[override]
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        n = len(self.labels)
        if not -n <= i < n:
            raise IndexError(f"sample {i} out of range: the set has {n} samples")
        label = self.labels[i]
        sample: Sample = {
            "index": label["index"],
            "image": _load_image(self.root / label["image"]),
            "labels": label,
        }
        if label.get("depth"):
            sample["depth"] = np.load(self.root / label["depth"])
        if label.get("mask"):
            sample["mask"] = _load_image(self.root / label["mask"])[..., 0] > 127
        if label.get("reference"):
            sample["reference"] = _load_image(self.root / label["reference"])
        return self.transform(sample) if self.transform is not None else sample

    def __repr__(self) -> str:
        return f"geltip.Dataset({str(self.root)!r}, {len(self)} samples)"


def _load_image(path: Path) -> np.ndarray:
    from ._geltip import load_image

    return load_image(path)
