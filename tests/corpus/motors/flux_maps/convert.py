"""Convert published flux maps (MATLAB files) to the toolbox's flux-map CSV
(toolbox/spec/_flux_map.py): ``i_d, i_q, psi_d, psi_q`` over a rectangular
grid, PMSM axes (magnet flux on +d), peak-value dq quantities.

Run it again to reproduce the CSV files here byte for byte (README.md says
where each MATLAB file comes from and its SHA-256)::

    python convert.py syre THOR.mat syre_thor_5kw.csv --stride 5
    python convert.py grid ABB_400rpm_map.mat baldor_ecs101m0h7ef4_400rpm.csv

``syre``: a SyR-e motor model (``motorModel.FluxMap_dq``), the same steps as
motulator 0.5.0 ``motulator.drive.utils.import_syre_data``:

1. SyR-e stores its maps in the synchronous-reluctance axes (``axisType =
   'SR'``: the high-permeance axis is d, the magnets on -q). PMSM axes:
   ``i_d = -Iq_syre``, ``i_q = Id_syre``, ``psi_d = -Fq_syre``,
   ``psi_q = Fd_syre``; rows are re-ordered so that i_d increases.
2. SyR-e computes the half plane ``i_q >= 0`` (PMSM axes). The half plane
   ``i_q < 0`` follows from the magnetic symmetry about the d axis:
   ``psi_d(i_d, -i_q) = psi_d(i_d, i_q)``, ``psi_q(i_d, -i_q) = -psi_q(i_d, i_q)``;
   the ``i_q = 0`` line is kept once, as SyR-e computed it.
3. Every ``stride``-th grid line is kept in each axis (the 256 x 256 grid has
   255 steps: a stride dividing 255 keeps both ends and the grid's symmetry).

Check on the way: the map's torque ``3/2 p (psi_d i_q - psi_q i_d)`` equals the
FEA torque stored in the same file (``FluxMap_dq.T``) within 1 % wherever
``|T| > 2 N m`` inside the current limit ``data.Imax`` (THOR: 0.47 % at most).

``grid``: a measured map stored as four equal-shape matrices ``id_map``,
``iq_map``, ``psid_map``, ``psiq_map`` (PMSM axes already; motulator 0.5.0
``examples/drive/flux_vector/ABB_400rpm_map.mat``), written as it is.

No value is interpolated or smoothed: every flux in a CSV is a value of the
source file (or its mirror image by step 2), printed with 8 significant digits.
"""

from __future__ import annotations

import argparse
import hashlib
from pathlib import Path

import numpy as np
from scipy.io import loadmat


def syre_grid(path: Path, stride: int):
    """The SyR-e flux map in PMSM axes over both half planes:
    (i_d, i_q, psi_d, psi_q), psi_*[j, k] at (i_d[j], i_q[k])."""
    model = loadmat(path)["motorModel"][0, 0]
    fm = model["FluxMap_dq"][0, 0]
    Id, Iq, Fd, Fq, T = (np.asarray(fm[k], float) for k in ("Id", "Iq", "Fd", "Fq", "T"))
    # SyR-e grids: Id varies along axis 1, Iq along axis 0
    assert np.ptp(Id, axis=0).max() == 0 and np.ptp(Iq, axis=1).max() == 0
    # check: the FEA torque T equals 3/2 p (Fd Iq - Fq Id) (SyR-e axes) within 1 %
    # wherever |T| > 2 N m inside the drive's current limit data.Imax
    p = float(model["data"][0, 0]["p"].ravel()[0])
    imax = float(model["data"][0, 0]["Imax"].ravel()[0])
    inside = (np.hypot(Id, Iq) <= imax) & (np.abs(T) > 2.0)
    err = np.abs(1.5 * p * (Fd * Iq - Fq * Id) - T)[inside] / np.abs(T[inside])
    print(f"flux-torque vs FEA torque inside |i| <= {imax:g} A: max {err.max():.2%}")
    assert err.max() < 0.01
    i_d, i_q = -Iq[:, 0], Id[0, :]
    psi_d, psi_q = -Fq, Fd
    order = np.argsort(i_d)
    i_d, psi_d, psi_q = i_d[order], psi_d[order], psi_q[order]
    if (len(i_d) - 1) % stride or (len(i_q) - 1) % stride:
        raise SystemExit(f"stride {stride} does not divide {len(i_d) - 1}")
    s = stride
    i_d, i_q, psi_d, psi_q = i_d[::s], i_q[::s], psi_d[::s, ::s], psi_q[::s, ::s]
    assert i_q[0] == 0.0
    return (i_d, np.concatenate((-i_q[:0:-1], i_q)),
            np.concatenate((psi_d[:, :0:-1], psi_d), axis=1),
            np.concatenate((-psi_q[:, :0:-1], psi_q), axis=1))


def matrix_grid(path: Path):
    """A measured map stored as id_map, iq_map, psid_map, psiq_map (i_d
    constant along axis 1, i_q along axis 0)."""
    m = loadmat(path)
    idm, iqm, pd, pq = (np.asarray(m[k], float)
                        for k in ("id_map", "iq_map", "psid_map", "psiq_map"))
    assert np.ptp(idm, axis=1).max() == 0 and np.ptp(iqm, axis=0).max() == 0
    return idm[:, 0] + 0.0, iqm[0, :] + 0.0, pd, pq   # + 0.0: no "-0" in the CSV


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("kind", choices=("syre", "grid"))
    ap.add_argument("mat", type=Path)
    ap.add_argument("csv", type=Path)
    ap.add_argument("--stride", type=int, default=5, help="syre: keep every n-th grid line")
    args = ap.parse_args()
    if args.kind == "syre":
        i_d, i_q, psi_d, psi_q = syre_grid(args.mat, args.stride)
        how = f"convert.py syre --stride {args.stride}"
    else:
        i_d, i_q, psi_d, psi_q = matrix_grid(args.mat)
        how = "convert.py grid"
    digest = hashlib.sha256(args.mat.read_bytes()).hexdigest()
    lines = [
        f"# Flux map converted from {args.mat.name}",
        f"# (SHA-256 {digest}) by {how};",
        "# PMSM axes (magnet flux on +d), peak-value dq quantities; see README.md.",
        "i_d [A],i_q [A],psi_d [Wb],psi_q [Wb]",
    ]
    for j, d in enumerate(i_d):
        for k, q in enumerate(i_q):
            lines.append(f"{d:.6f},{q:.6f},{psi_d[j, k]:.7e},{psi_q[j, k]:.7e}")
    args.csv.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"{args.csv}: {len(i_d)} i_d x {len(i_q)} i_q = {len(i_d) * len(i_q)} points")


if __name__ == "__main__":
    main()
