"""Exporting a solved photon lattice as EXR + JSON that other tools can read (docs/baking.md,
"Export Volume").

Probe grids export natively (``ProbeField.export(json_path)``, probes/probe_storage.h); this is
the same format family for ``PhotonLattice``: ``<stem>.json`` beside one EXR per lattice,
``<stem>_global.exr`` (low-frequency light of the global photon map) and
``<stem>_caustic.exr`` (the fine caustic lattice). A lattice of dims (nx, ny, nz) is an EXR
nx pixels wide and ny * nz high; cell (i, j, k) is pixel column i, row j + ny * k (row 0 the
file's first row), with float channels ``sh<ii>.R/G/B`` for coefficient ii = l(l+1)+m. The
JSON states the format, version, frame, SH basis, normalisation and units, and each lattice's
origin, cell size, dims and file.
"""

from __future__ import annotations

import json
import os

import numpy as np

from . import _shgi

FORMAT = "shgi-sh-lattice"
VERSION = 1


def export_lattice(lattice, json_path: str) -> list:
    """Writes `lattice` (a solved shgi.PhotonLattice); returns the paths written.

    Raises ValueError for a path not ending in .json or a lattice never solved, OSError when a
    file cannot be written.
    """
    json_path = os.fspath(json_path)
    if not json_path.endswith(".json"):
        raise ValueError(f"export_lattice: {json_path!r} must end in .json")
    if lattice.passes == 0:
        raise ValueError("export_lattice: the lattice holds no light yet; call solve() first")
    stem = json_path[: -len(".json")]
    entries, paths = [], []
    for name, data in lattice.lattices.items():
        sh = np.asarray(data["sh"], np.float32)  # (nz, ny, nx, coefficients, 3)
        nz, ny, nx, coefficients, _ = sh.shape
        image = sh.reshape(nz * ny, nx, coefficients, 3)  # row j + ny * k, column i
        layers = {f"sh{c:02d}": np.ascontiguousarray(image[:, :, c, :])
                  for c in range(coefficients)}
        path = f"{stem}_{name}.exr"
        _shgi.write_exr(path, layers, pixel_type="float")
        paths.append(path)
        entries.append({"name": name, "origin": list(data["origin"]),
                        "cell_size": data["cell_size"], "dims": list(data["dims"]),
                        "order": data["order"], "coefficients": coefficients,
                        "sh_file": os.path.basename(path)})
    doc = {
        "format": FORMAT,
        "version": VERSION,
        "frame": "Blender world space: right-handed, Z up, metres",
        "sh": {
            "quantity": "indirect incident radiance (light that scattered at least once; add "
                        "direct light separately), per lattice cell; sum the lattices",
            "unit": "W m^-2 sr^-1, linear Rec.709 RGB",
            "basis": "real orthonormal spherical harmonics without the Condon-Shortley phase; "
                     "coefficient index i = l(l+1)+m; Y00 = 0.282095, Y1-1 = 0.488603 y, "
                     "Y10 = 0.488603 z, Y11 = 0.488603 x (Ramamoorthi-Hanrahan)",
            "normalisation": "L(w) = sum_i c_i Y_i(w); irradiance E(n) = sum_lm A_l c_lm "
                             "Y_lm(n) with A_0..A_2 = pi, 2pi/3, pi/4",
            "channels": "sh<ii>.R/G/B, ii = two-digit coefficient index",
        },
        "layout": "cell (i, j, k) centred at origin + (i + 0.5, j + 0.5, k + 0.5) * cell_size; "
                  "in its EXR at pixel column i, row j + ny * k (row 0 first in the file); "
                  "cells without surface hold 0",
        "passes": lattice.passes,
        "lattices": entries,
    }
    temp = json_path + ".partial"
    with open(temp, "w", encoding="utf-8") as out:
        json.dump(doc, out, indent=2)
        out.write("\n")
    os.replace(temp, json_path)
    return [json_path] + paths
