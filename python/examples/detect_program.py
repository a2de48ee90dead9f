"""The NumPy detector of evaluate_detector.py as a program that `geltip evaluate` runs.

    geltip evaluate --suite paper --sensor paper --detector "python3 python/examples/detect_program.py" --out eval/program

geltip writes one JSON line per frame on stdin ({"sample", "image", "reference", "sensor"}:
paths) and reads one line back ({"detections": [...]}); end of input ends the program.
"""
import json
import os
import sys

import geltip

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from evaluate_detector import detect  # noqa: E402  (the function the README shows)

for line in sys.stdin:
    frame = json.loads(line)
    image = geltip.load_image(frame["image"])
    reference = geltip.load_image(frame["reference"])
    found = detect(image, reference, geltip.Sensor.from_toml(frame["sensor"]))
    print(json.dumps({"detections": found}), flush=True)
