"""The vision tools: a blob locator, a pattern locator and an inspection, on OpenCV.

Each tool reads the metric top view of its plane (view.py) and returns ``Instance``s in
robot coordinates (mm, degrees).  Parameters come from the cell file, one ``[[vision.process]]``
per job (process.py).

* Blob: threshold, outer contours, area moments -> centroid and area; the minimum-area
  rectangle -> width, length and the angle of the long side (modulo 180, modulo 90 for a
  square); score = area over that rectangle's area (1 for a rectangle).
* Pattern: normalised cross-correlation with a model drawn from the part's outline (its
  CAD polygon, mm), rotated over the full turn: a coarse search on a reduced view, then
  angle and position refined on the full view with a parabola through the best scores.
  With ``mirror = true`` the mirror image is tried too, and an instance that matches it
  better is reported as the mirrored model: a flat part lying upside down.
* Inspection: a measured property of another tool's instances (area, width, length,
  score) within [min, max].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .view import PlaneView


@dataclass
class Instance:
    """One thing a tool found (robot frame): pose, score 0..1, measures, the outline in view
    pixels for drawing, and what an inspection made of it."""

    x: float
    y: float
    z: float
    angle: float  # deg, yaw in the robot frame
    score: float
    area: float = 0.0  # mm^2
    width: float = 0.0  # mm (short side)
    length: float = 0.0  # mm (long side)
    model: str = ""  # pattern: which model matched
    outline: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))  # view (column, row)
    passed: bool | None = None  # inspection
    actual: float | None = None

    def measure(self, name: str) -> float:
        """An inspected property; ``upright`` is 1 unless a pattern matched the mirror image."""
        if name == "upright":
            return 0.0 if self.model.endswith("mirrored") else 1.0
        if name not in ("area", "width", "length", "score", "angle"):
            raise ValueError(f"inspection: no property {name!r} (area, width, length, score, angle, upright)")
        return float(getattr(self, name))


def _wrap180(a: float) -> float:
    return (a + 180.0) % 360.0 - 180.0


@dataclass
class BlobLocator:
    threshold: int = 128  # grey level
    polarity: str = "bright"  # "bright": parts brighter than the background, or "dark"
    min_area: float = 50.0  # mm^2
    max_area: float = 1e9
    sort: str = "x"  # order of the instances: "x", "y", "area", "score"

    def run(self, view: PlaneView, image: np.ndarray) -> list[Instance]:
        flag = cv2.THRESH_BINARY if self.polarity == "bright" else cv2.THRESH_BINARY_INV
        _, mask = cv2.threshold(image, self.threshold, 255, flag)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        s = view.scale
        rows, cols = image.shape
        unseen = view.unseen()
        found = []
        for contour in contours:
            pts = contour.reshape(-1, 2).astype(np.float32)
            m = cv2.moments(pts)
            area = m["m00"] * s * s
            if not self.min_area <= area <= self.max_area or m["m00"] <= 0:
                continue
            x0, y0, w, h = cv2.boundingRect(contour)
            if x0 <= 0 or y0 <= 0 or x0 + w >= cols - 1 or y0 + h >= rows - 1:
                continue  # cut by the edge of the view: not a whole part
            if unseen[contour[:, 0, 1], contour[:, 0, 0]].any():
                continue  # cut by the edge of the picture (the view reaches beyond it)
            cx, cy = m["m10"] / m["m00"], m["m01"] / m["m00"]
            angle, width, length = _rectangle(pts, s)
            x, y = view.to_robot([cx, cy])[0]
            found.append(Instance(x=float(x), y=float(y), z=view.z, angle=_wrap180(angle),
                                  score=float(min(1.0, area / max(width * length, 1e-9))), area=float(area),
                                  width=float(width), length=float(length), outline=pts))
        return _sorted(found, self.sort)


def _rectangle(pts: np.ndarray, scale: float) -> tuple[float, float, float]:
    """Angle of the long side (deg, modulo 180; modulo 90 for a square, within 5 %) and the
    width and length (mm) of the minimum-area rectangle around a contour."""
    (_, _), (w, h), a = cv2.minAreaRect(pts)
    if w < h:
        w, h, a = h, w, a + 90.0
    a = _wrap180(a)
    a = a - 180.0 if a > 90.0 else a + 180.0 if a <= -90.0 else a
    if h > 0.95 * w:
        a = (a + 45.0) % 90.0 - 45.0
    return a, h * scale, w * scale


def _sorted(found: list[Instance], key: str) -> list[Instance]:
    if key not in ("x", "y", "area", "score"):
        raise ValueError(f"sort: {key!r} is not x, y, area or score")
    reverse = key in ("area", "score")
    return sorted(found, key=lambda i: (getattr(i, key), i.x, i.y), reverse=reverse)


NEAR_MM = 6.0  # a pattern searched near another tool's instance: how far its origin may be


@dataclass
class PatternLocator:
    outline: list[list[float]]  # the part's outline, mm, in its own frame (x along the part)
    min_score: float = 0.6
    mirror: bool = False  # also try the mirror image (a flat part upside down)
    coarse_step: float = 6.0  # deg
    coarse_scale: float = 1.0  # mm per pixel of the coarse search
    max_instances: int = 50
    sort: str = "x"
    name: str = "pattern"
    _models: dict = field(default_factory=dict, repr=False)

    def _model(self, scale: float, angle: float, mirrored: bool, cache: bool = False) -> np.ndarray:
        """The outline drawn filled (anti-aliased) at ``scale`` mm/pixel, turned by angle;
        the coarse search's angles are kept (``cache``), refined ones drawn each time."""
        key = (scale, round(angle, 6), mirrored)
        if key not in self._models:
            poly = np.array(self.outline, dtype=np.float64)
            if mirrored:
                poly = poly * [1.0, -1.0]
            a = math.radians(angle)
            R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            pts = poly @ R.T / scale
            radius = np.max(np.linalg.norm(poly, axis=1)) / scale + 3
            size = int(2 * math.ceil(radius) + 1)
            centre = size // 2
            img = np.zeros((size, size), np.uint8)
            shift = 4  # fixed-point bits of cv2.fillPoly
            cv2.fillPoly(img, [np.round((pts + centre) * (1 << shift)).astype(np.int32)], 255,
                         lineType=cv2.LINE_AA, shift=shift)
            if not cache:
                return img
            self._models[key] = img
        return self._models[key]

    def _scores(self, image: np.ndarray, scale: float, angle: float, mirrored: bool, cache: bool = False) -> np.ndarray:
        model = self._model(scale, angle, mirrored, cache)
        if image.shape[0] < model.shape[0] or image.shape[1] < model.shape[1]:
            return np.full((1, 1), -1.0, np.float32)
        return cv2.matchTemplate(image, model, cv2.TM_CCOEFF_NORMED)

    def run(self, view: PlaneView, image: np.ndarray, near: list[Instance] | None = None) -> list[Instance]:
        """All instances in the view, or one per instance of ``near`` (another tool's, the
        search limited to around each; an instance not matched gets score 0)."""
        if near is None:
            candidates = self._coarse(view, image)
            found = [f for f in (self._refine(view, image, c) for c in candidates) if f.score >= self.min_score]
            return _sorted(found[:self.max_instances], self.sort)
        out = []
        half = self._model(view.scale, 0.0, False, cache=True).shape[0] // 2
        for inst in near:
            c, r = int(round((inst.x - view.lo[0]) / view.scale)), int(round((inst.y - view.lo[1]) / view.scale))
            pad = half + int(round(NEAR_MM / view.scale))  # the model's origin within NEAR_MM of the instance
            r0, c0 = max(0, r - pad), max(0, c - pad)
            roi = image[r0:r + pad + 1, c0:c + pad + 1]
            candidates = self._coarse(view, roi)[:1]
            best = Instance(x=inst.x, y=inst.y, z=view.z, angle=inst.angle, score=0.0)
            if candidates:
                centre, angle, mirrored = candidates[0]
                found = self._refine(view, image, (centre + [c0, r0], angle, mirrored))
                if found.score >= self.min_score:
                    best = found
            out.append(best)
        return out

    def _coarse(self, view: PlaneView, image: np.ndarray) -> list[tuple[np.ndarray, float, bool]]:
        k = max(1, int(round(self.coarse_scale / view.scale)))
        small = cv2.resize(image, (image.shape[1] // k, image.shape[0] // k), interpolation=cv2.INTER_AREA)
        scale = view.scale * k
        best_score, best_angle, best_mirror = None, None, None
        for mirrored in ((False, True) if self.mirror else (False,)):
            for angle in np.arange(0.0, 360.0, self.coarse_step):
                s = self._scores(small, scale, angle, mirrored, cache=True)
                if best_score is None:
                    best_score = s.copy()
                    best_angle = np.full(s.shape, angle)
                    best_mirror = np.full(s.shape, mirrored)
                else:
                    better = s > best_score
                    best_score[better] = s[better]
                    best_angle[better] = angle
                    best_mirror[better] = mirrored
        # Peaks: local maxima over the part's size, above a lowered threshold.
        radius = int(np.min(np.ptp(np.array(self.outline), axis=0)) / scale / 2) | 1
        dilated = cv2.dilate(best_score, np.ones((2 * radius + 1, 2 * radius + 1), np.uint8))
        rows, cols = np.nonzero((best_score >= dilated) & (best_score >= self.min_score * 0.8))
        order = np.argsort(-best_score[rows, cols])[: self.max_instances * 2]
        half = self._model(scale, 0.0, False, cache=True).shape[0] // 2
        return [(np.array([cols[i] + half, rows[i] + half], float) * k, float(best_angle[rows[i], cols[i]]),
                 bool(best_mirror[rows[i], cols[i]])) for i in order]

    def _refine(self, view: PlaneView, image: np.ndarray, candidate, search_px: int | None = None) -> Instance:
        """Best angle (steps of coarse/6, then a parabola) and position (parabola) near a
        candidate, on the full view."""
        centre, start, mirrored = candidate
        model_half = self._model(view.scale, 0.0, mirrored, cache=True).shape[0] // 2
        pad = search_px if search_px is not None else int(self.coarse_scale / view.scale) * 3 + 2
        r0 = int(round(centre[1])) - model_half - pad
        c0 = int(round(centre[0])) - model_half - pad
        size = 2 * (model_half + pad) + 1
        if r0 < 0 or c0 < 0 or r0 + size > image.shape[0] or c0 + size > image.shape[1]:
            return Instance(x=0.0, y=0.0, z=view.z, angle=0.0, score=-1.0)
        roi = image[r0:r0 + size, c0:c0 + size]
        step = self.coarse_step / 6
        angles = start + np.arange(-6, 7) * step
        peaks = []
        for a in angles:
            s = self._scores(roi, view.scale, a, mirrored)
            r, c = np.unravel_index(int(np.argmax(s)), s.shape)
            peaks.append((float(s[r, c]), r, c, s))
        k = int(np.argmax([p[0] for p in peaks]))
        score, r, c, s = peaks[k]
        angle = angles[k]
        if 0 < k < len(angles) - 1:
            angle += step * _vertex(peaks[k - 1][0], score, peaks[k + 1][0])
            s = self._scores(roi, view.scale, angle, mirrored)
            r, c = np.unravel_index(int(np.argmax(s)), s.shape)
            score = float(s[r, c])
        dr = _vertex(s[r - 1, c], s[r, c], s[r + 1, c]) if 0 < r < s.shape[0] - 1 else 0.0
        dc = _vertex(s[r, c - 1], s[r, c], s[r, c + 1]) if 0 < c < s.shape[1] - 1 else 0.0
        half = self._model(view.scale, angle, mirrored).shape[0] // 2
        col, row = c0 + c + dc + half, r0 + r + dr + half
        x, y = view.to_robot([col, row])[0]
        outline = np.array(self.outline) * ([1.0, -1.0] if mirrored else [1.0, 1.0])
        a = math.radians(angle)
        R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        drawn = outline @ R.T / view.scale + [col, row]
        return Instance(x=float(x), y=float(y), z=view.z, angle=_wrap180(float(angle)), score=score,
                        model=f"{self.name}{' mirrored' if mirrored else ''}", outline=drawn.astype(np.float32))


def _vertex(a: float, b: float, c: float) -> float:
    """Offset (-0.5..0.5) of the top of the parabola through three equally spaced values."""
    d = a - 2 * b + c
    return 0.0 if d >= 0 else float(np.clip(0.5 * (a - c) / d, -0.5, 0.5))


@dataclass
class Inspection:
    source: str  # the tool whose instances are inspected
    property: str  # area, width, length, score
    min: float = -math.inf
    max: float = math.inf

    def run(self, instances: list[Instance]) -> list[Instance]:
        out = []
        for inst in instances:
            value = inst.measure(self.property)
            out.append(Instance(**{**inst.__dict__, "passed": bool(self.min <= value <= self.max), "actual": value}))
        return out
