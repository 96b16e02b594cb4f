"""The voltage placement in the header (toolbox/ARCHITECTURE.md "The digital
loop"): the placement time, its convention as written in the comment, and
the integer variants' Q30 placement constant (``templates/placement.c.j2``)."""

from __future__ import annotations

import math

from ..errors import ExportRefused
from ._format import _int


def _delay_comp_time(artifact) -> float | None:
    """The voltage placement's rotation time (s), or None when it is 0.

    The typed ``decoupling.delay_compensation_time`` (``drive.angle_compensation``,
    toolbox/ARCHITECTURE.md "The digital loop").
    """
    t_comp = artifact.decoupling.delay_compensation_time
    return float(t_comp) if t_comp > 0 else None


def _placement_convention(artifact) -> str:
    """``drive.angle_compensation`` as written in the header's comment."""
    t_comp = artifact.decoupling.delay_compensation_time
    if t_comp == 0:
        return '"none"'
    if math.isclose(t_comp, (artifact.delay_samples + 0.5) * artifact.sample_time,
                    rel_tol=1e-12):
        return '"mid_period"'
    return f"{t_comp:.9g} s"


#: Largest placement angle (rad, at the speed base) of the integer variants'
#: Taylor rotation: its truncation error (x^8/8!) stays below 1e-4 up to here.
Q31_MAX_PLACEMENT_ANGLE = 1.5


def _integer_placement(artifact, w_base: float, w_reach: float | None = None) -> dict | None:
    """An integer variant's voltage placement constant, or None when the
    placement time is 0: ``K`` is the rotation angle at the variant's
    full-scale mechanical speed ``w_base`` (``DELAY_COMP_TIME p w_base``) in
    Q30 radians (``templates/placement.c.j2``), below 2^33 (the int64 product
    with a speed word of at most 2^30 cannot overflow). ``w_reach`` (default
    ``w_base``): the largest speed the step rotates with (the range it clamps
    the speed to), where the angle must stay within ``Q31_MAX_PLACEMENT_ANGLE``."""
    t_comp = _delay_comp_time(artifact)
    if t_comp is None:
        return None
    w_reach = w_base if w_reach is None else w_reach
    angle = t_comp * artifact.decoupling.pole_pairs * w_base
    reach = t_comp * artifact.decoupling.pole_pairs * w_reach
    if reach > Q31_MAX_PLACEMENT_ANGLE:
        raise ExportRefused("drive.angle_compensation",
                            f"a placement angle of at most {Q31_MAX_PLACEMENT_ANGLE} rad at "
                            "the integer variants' speed range (DELAY_COMP_TIME x POLE_PAIRS "
                            "x speed range)", f"{reach:.3g} rad")
    return {"K": _int(round(angle * 2.0 ** 30), 'drive.angle_compensation',
                      'placement angle constant', 0, 2 ** 33 - 1),
            "angle": f"{angle:.6g}"}
