"""Reading what an animation page carries: its JSON data block and the float32 arrays in it
(shared by the animation tests)."""
from __future__ import annotations

import base64
import json
import re

import numpy as np


def page_data(path) -> dict:
    text = path.read_text(encoding="utf-8")
    m = re.search(r'<script id="pmd-data" type="application/json">(.*?)</script>', text, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def f32(b64: str) -> np.ndarray:
    return np.frombuffer(base64.b64decode(b64), dtype="<f4")
