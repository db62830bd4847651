"""What the shape fits (bodies of revolution, boxes) share: the size of a fit's point
subsample, the axis tilts that name a pose, and the confidence a fit's errors give."""

from __future__ import annotations

import math

import numpy as np

FIT_POINTS = 400  # surface points used to fit an axis (an even subsample)
UPRIGHT_TILT = math.radians(12)  # an axis nearer the vertical than this is standing
LYING_TILT = math.radians(65)  # ... farther than this, lying; between them, leaning
MAX_ERROR = 2.0  # [tolerances] one measurement off by more rules a fit out: the
#                         mean square dilutes it (a lego brick 13 mm taller than a lying
#                         carton, its other sizes close, scored 0.34); at 2.5, 10 false
#                         detections in 528 bench views, at 2.0 6, one true view fewer


def _confidence(z: np.ndarray) -> float:
    """Confidence from measurement errors ``z`` in units of their tolerances: a Gaussian
    of their mean square, at most 0.1 when any is off by more than MAX_ERROR."""
    conf = float(math.exp(-0.5 * float(np.mean(z * z))))
    return min(conf, 0.1) if np.any(np.abs(z) > MAX_ERROR) else conf
