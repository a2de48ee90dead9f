"""`geltip.evaluate`: score any contact detector against the exact labels, with the same
protocol, files and tables as ``geltip evaluate`` (see docs/evaluate.md).

    import geltip

    def detect(image, reference, sensor):      # (H, W, 3) uint8 arrays, a geltip.Sensor
        ...
        return [{"pixel": [u, v], "confidence": 0.8}]   # or {"point": [x, y, z]} in mm

    report = geltip.evaluate(detect, suite="paper", sensor="paper", out="eval/mine")
    print(report.tables)
    report.summary["recall"], report.summary["error_mm"]["median"]
"""
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _geltip

Detection = Dict[str, Any]
Detector = Callable[[np.ndarray, np.ndarray, "_geltip.Sensor"], Sequence[Detection]]


@dataclass(frozen=True)
class EvaluationReport:
    """What `evaluate` measured: ``summary`` is ``summary.json``'s dict, ``tables`` the
    Markdown tables, ``per_sample`` one dict per frame (``per_sample.jsonl``), ``files``
    the names written in ``out``."""

    summary: Dict[str, Any]
    tables: str
    per_sample: List[Dict[str, Any]] = field(repr=False)
    files: List[str]

    def __repr__(self) -> str:
        s = self.summary
        recall = s.get("recall")
        recall = "-" if recall is None else f"{recall:.3f}"
        return (
            f"EvaluationReport(detector={s.get('detector')!r}, samples={s.get('samples')}, "
            f"recall={recall}, false_positives={s.get('false_positives')})"
        )


def evaluate(
    detector: Union[Detector, str],
    *,
    dataset: Optional[Union[str, PathLike]] = None,
    suite: Optional[str] = None,
    sensor: Optional[Union[str, PathLike, "_geltip.Sensor"]] = None,
    out: Optional[Union[str, PathLike]] = None,
    gate_mm: Optional[float] = 3.0,
    name: Optional[str] = None,
    compare: Optional[Union[str, PathLike]] = None,
    real: Optional[Union[str, PathLike]] = None,
    threshold: Optional[float] = None,
    noise: Optional[float] = None,
    area_mm2: Optional[Tuple[float, float]] = None,
) -> EvaluationReport:
    """Scores ``detector`` on a set from ``geltip dataset`` (``dataset=``), a suite
    rendered on the fly (``suite="paper"`` or ``"stability"``, with ``sensor=``), or a real
    sensor's labelled frames (``real=``: a set file or the AllSight ``labels.json``, with the
    ``sensor=`` that took them; ``summary["rows"]`` per group, ``per_sample`` empty).

    ``detector(image, reference, sensor)`` gets each frame and its empty frame as
    (H, W, 3) uint8 arrays and the frame's ``geltip.Sensor``, and returns a list of
    detections: dicts with ``"pixel": [u, v]`` or ``"point": [x, y, z]`` (mm, camera
    frame) and an optional ``"confidence"``. ``"surface"``, ``"paper"`` or ``"change"`` names a
    built-in localiser instead (``threshold``: the change method's decision threshold, in
    noise spreads; ``noise``: the sensor's noise in 8-bit levels, a floor under each pair's
    own estimate; ``area_mm2``: (min, max) of the contact's area on the finger, for
    ``"change"`` and ``"paper"``). Detections are matched one to one to the visible
    contacts within ``gate_mm`` (None: any distance). With ``out``, the report's files
    (summary.json, per_sample.jsonl, tables.md, charts) are written there, beside
    ``compare``'s (another run's output directory). An exception the detector raises
    stops the run and is raised again.
    """
    r = _geltip.evaluate(
        detector,
        dataset=dataset,
        suite=suite,
        sensor=sensor,
        out=out,
        gate_mm=gate_mm,
        name=name,
        compare=compare,
        real=real,
        threshold=threshold,
        noise=noise,
        area_mm2=area_mm2,
    )
    return EvaluationReport(
        summary=r["summary"], tables=r["tables"], per_sample=r.get("per_sample", []),
        files=r["files"],
    )
