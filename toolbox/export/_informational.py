"""The PI gains a header states "for information only": the parallel-form
``Kp``, ``Ki`` of each PI-type axis of a PI method, read from the executed law."""

from __future__ import annotations

from ._check import AXES, _is_integrator


PI_METHODS = ("pi", "ip", "pi_lag", "robust_pi", "tune")


def _pi_gains(artifact, ax: str) -> tuple[float, float] | None:
    """Parallel-form (Kp V/A, Ki V/(A s)) of a PI-type axis, or None.

    Read from the executed law, never from informational design parameters:
    the continuous error controller ``Kp + Ki/s`` (one state, an integrator)
    when there is one, else the discrete one with the discretisation's
    feedthrough correction. Laws of another structure (a lag, 2 states)
    export no KP/KI defines; the law below them is what runs anyway.
    """
    axc = artifact.axes[ax]
    if axc.continuous is not None and axc.continuous.order == 1 \
            and abs(axc.continuous.A[0, 0]) < 1e-12:
        c = axc.continuous
        return float(c.D[0, 0]), float(c.C[0, 0] * c.B[0, 0])
    dsc = axc.discrete
    if dsc.order == 1 and _is_integrator(dsc.A[0, 0]):
        kits = float(dsc.C[0, 0] * dsc.B[0, 0])
        corr = {"tustin": 0.5, "backward_diff": 1.0}.get(dsc.method or "", 0.0)
        return float(dsc.D[0, 0]) - corr * kits, kits / artifact.sample_time
    return None


def _informational_pi_gains(artifact) -> list[tuple[str, float, float]]:
    """``(axis, Kp, Ki)`` of each PI-type axis (:func:`_pi_gains`) of a PI
    method, for the comments marked "for information only"; empty otherwise."""
    if artifact.method not in PI_METHODS:
        return []
    return [(ax, *g) for ax in AXES if (g := _pi_gains(artifact, ax)) is not None]
