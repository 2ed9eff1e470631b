"""People found in a delivered frame by a detector trained on real photographs.

The detector is OpenCV's HOG people detector (Dalal & Triggs 2005, "Histograms of Oriented Gradients
for Human Detection"; its linear SVM is trained on the INRIA Person data set of real photographs). It
ships compiled into OpenCV's contrib build (`opencv-contrib-python-headless`), so no weights are
downloaded. Its 64×128 window finds people about 96 px tall and taller, so frames are upscaled by
`UPSCALE` first (people from about 64 px). HOG's boxes include the window's margin; they are shrunk as OpenCV's
peopledetect sample does (15 % of the width and 5 % of the height on each side).
"""

from __future__ import annotations

import cv2
import numpy as np

UPSCALE = 1.5
"""Factor frames are enlarged by before detection."""
HIT_THRESHOLD = 0.0
"""Least SVM score (distance to its hyperplane) of a detection; OpenCV's default."""


def hog_detector():
    """OpenCV's default HOG people detector, or None when this OpenCV build lacks it (OpenCV 5 moved
    HOG to its contrib build)."""
    if not hasattr(cv2, "HOGDescriptor"):
        return None
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
    return hog


def detect_people(hog, bgr: np.ndarray) -> list[tuple[float, float, float, float, float]]:
    """(x0, y0, x1, y1, score) boxes of people in an 8-bit (H, W, 3) BGR frame, in pixel-edge
    coordinates of the frame (pixel u covers [u, u + 1)); score is the SVM's, unbounded, higher surer."""
    big = cv2.resize(bgr, None, fx=UPSCALE, fy=UPSCALE, interpolation=cv2.INTER_LINEAR)
    rects, weights = hog.detectMultiScale(big, hitThreshold=HIT_THRESHOLD, winStride=(8, 8), padding=(8, 8), scale=1.05)
    out = []
    for (x, y, w, h), score in zip(rects, np.ravel(weights), strict=True):
        pad_w, pad_h = 0.15 * w, 0.05 * h
        out.append(((x + pad_w) / UPSCALE, (y + pad_h) / UPSCALE, (x + w - pad_w) / UPSCALE, (y + h - pad_h) / UPSCALE,
                    float(score)))  # fmt: skip
    return out
