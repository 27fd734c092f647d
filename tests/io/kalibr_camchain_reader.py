#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Loads a camchain YAML as Kalibr's config reader does (kalibr_common/ConfigReader.py:
CameraChainParameters over CameraParameters) and exits 1 naming the first violation.

Usage: kalibr_camchain_reader.py CAMCHAIN [--metric]
  --metric: the translations must be in metres (rigcal_translation_unit: m).
"""
import sys

import yaml

# Kalibr's camera and distortion models with the lengths of their parameter lists.
CAMERA_MODELS = {"pinhole": 4, "omni": 5, "eucm": 6, "ds": 6}
DISTORTION_MODELS = {"radtan": 4, "equidistant": 4, "fov": 1, "none": 0}


class SchemaError(Exception):
    pass


def check_camera(name, cam, first):
    for key in ("camera_model", "intrinsics", "distortion_model", "distortion_coeffs",
                "resolution"):
        if key not in cam:
            raise SchemaError(f"{name}: no {key}")
    model = cam["camera_model"]
    if model not in CAMERA_MODELS:
        raise SchemaError(f"{name}: camera_model {model!r} is not one of Kalibr's")
    intrinsics = [float(v) for v in cam["intrinsics"]]
    if len(intrinsics) != CAMERA_MODELS[model]:
        raise SchemaError(f"{name}: {model} needs {CAMERA_MODELS[model]} intrinsics")
    distortion = cam["distortion_model"]
    if distortion not in DISTORTION_MODELS:
        raise SchemaError(f"{name}: distortion_model {distortion!r} is not one of Kalibr's")
    if len(cam["distortion_coeffs"]) != DISTORTION_MODELS[distortion]:
        raise SchemaError(f"{name}: {distortion} needs {DISTORTION_MODELS[distortion]} coeffs")
    resolution = cam["resolution"]
    if len(resolution) != 2 or not all(isinstance(v, int) and v > 0 for v in resolution):
        raise SchemaError(f"{name}: resolution must be [width, height]")
    if first:
        return
    if "T_cn_cnm1" not in cam:
        raise SchemaError(f"{name}: no T_cn_cnm1")
    t = cam["T_cn_cnm1"]
    if len(t) != 4 or any(len(row) != 4 for row in t):
        raise SchemaError(f"{name}: T_cn_cnm1 is not 4x4")
    t = [[float(v) for v in row] for row in t]
    if any(abs(a - b) > 1e-12 for a, b in zip(t[3], [0, 0, 0, 1])):
        raise SchemaError(f"{name}: T_cn_cnm1's last row is not 0 0 0 1")
    r = [row[:3] for row in t[:3]]
    for i in range(3):  # R R^T = I
        for j in range(3):
            dot = sum(r[i][k] * r[j][k] for k in range(3))
            if abs(dot - (1.0 if i == j else 0.0)) > 1e-6:
                raise SchemaError(f"{name}: T_cn_cnm1's rotation is not orthonormal")
    det = (r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
           - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
           + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]))
    if det < 0:
        raise SchemaError(f"{name}: T_cn_cnm1's rotation is a reflection")


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    metric = "--metric" in sys.argv[2:]
    with open(sys.argv[1]) as f:
        chain = yaml.safe_load(f)
    try:
        if not isinstance(chain, dict) or "cam0" not in chain:
            raise SchemaError("no cam0")
        n = 0
        while f"cam{n}" in chain:
            cam = chain[f"cam{n}"]
            check_camera(f"cam{n}", cam, n == 0)
            if metric and cam.get("rigcal_translation_unit") != "m":
                raise SchemaError(f"cam{n}: translations not in metres")
            n += 1
        extra = [k for k in chain if not (k.startswith("cam") and k[3:].isdigit())]
        if extra or len(chain) != n:
            raise SchemaError(f"keys that are not cam0..cam{n - 1}: {extra}")
    except SchemaError as e:
        print(f"{sys.argv[1]}: not a Kalibr camchain: {e}", file=sys.stderr)
        return 1
    print(f"{sys.argv[1]}: a Kalibr camchain of {n} cameras")
    return 0


if __name__ == "__main__":
    sys.exit(main())
