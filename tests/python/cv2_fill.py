"""Render polygons and lines with OpenCV for rocc's cv2-parity test (tests/bev.rs).

Usage: python3 cv2_fill.py IN.json OUT.npy
IN.json: {"w": W, "h": H, "polys": [[[u, v], ...], ...], "lines": [[[u, v], [u, v]], ...]}
OUT.npy: uint8 (len(polys) + len(lines), H, W), one image per shape.
"""

import json
import sys

import cv2
import numpy as np

spec = json.load(open(sys.argv[1]))
w, h = spec["w"], spec["h"]
out = []
for poly in spec["polys"]:
    img = np.zeros((h, w), np.uint8)
    cv2.fillPoly(img, [np.array(poly, np.int32)], 1)
    out.append(img)
for (p0, p1) in spec["lines"]:
    img = np.zeros((h, w), np.uint8)
    cv2.line(img, tuple(p0), tuple(p1), 1, 1)
    out.append(img)
np.save(sys.argv[2], np.stack(out))
