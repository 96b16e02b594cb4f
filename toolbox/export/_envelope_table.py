"""The operating envelope's current references in the header: a table over
speed and torque, its Python mirror, and its C text.

The table (:func:`envelope_table`) holds the references of
:class:`toolbox.plant.OperatingEnvelope` (MTPA below base speed, field
weakening above, the torque limit where a request exceeds it; constant
``Ld``, ``Lq``, ``flux``, or :class:`toolbox.plant.SaturatedEnvelope` from a saturated
motor's magnetic model; ``OperatingEnvelope.HEADROOM`` of the voltage kept
for the loop, as the verification grid) at :data:`N_SPEED` speeds from 0 to
the table's top speed (``drive.max_speed``, else 2 x base speed, lowered to
the highest speed at which a zero-torque current still fits) and
:data:`N_TORQUE` torques from 0 to the torque limit at that speed.
:meth:`EnvelopeTable.reference` and the header's ``<p>envelope_ref``
interpolate it the same way: linearly in ``|speed|`` between rows, and within
a row linearly in the torque's fraction of the row's limit (the limit itself
interpolated between rows); the request is clamped to the limit. A negative
torque mirrors ``i_q`` (regenerating needs less voltage than motoring with
``R``, so the mirrored reference stays within the limit); a negative speed
uses ``|speed|``.

Memory: ``(N_SPEED + 2 N_SPEED N_TORQUE) x 4`` bytes of float constants
(1 564 bytes for 17 x 11) and one function.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import SpecError
from ._format import _f

__all__ = ["EnvelopeTable", "envelope_table", "envelope_section", "N_SPEED", "N_TORQUE",
           "TABLE_BYTES"]

#: Table speeds (rows) and torque fractions (columns).
N_SPEED = 17
N_TORQUE = 11
#: Bytes of float constants in the header.
TABLE_BYTES = 4 * (N_SPEED + 2 * N_SPEED * N_TORQUE)


@dataclass(frozen=True)
class EnvelopeTable:
    """Reference table: ``speed_step`` (mechanical rad/s between rows),
    ``t_max[N_SPEED]`` (N m, the torque limit per row), ``i_d``, ``i_q``
    ``[N_SPEED, N_TORQUE]`` (A) at the torques ``t_max[k] j / (N_TORQUE - 1)``;
    ``v_max`` (V) and ``i_max`` (A) of the envelope; ``source`` the model
    the references come from (the header's comment)."""

    speed_step: float
    t_max: np.ndarray
    i_d: np.ndarray
    i_q: np.ndarray
    v_max: float
    i_max: float
    source: str = "toolbox.plant.OperatingEnvelope, constant Ld, Lq, flux"

    @property
    def top_speed(self) -> float:
        return self.speed_step * (len(self.t_max) - 1)

    def reference(self, torque: float, speed: float) -> tuple[float, float, int]:
        """``(i_d, i_q, status)``: the header's interpolation in double
        precision; status 0, 1 (torque clamped to the limit) or 2 (speed
        beyond the table: its last row used)."""
        status = 0
        s = abs(speed) / self.speed_step
        n = len(self.t_max)
        if s > n - 1:
            s, status = float(n - 1), 2
        k = min(int(s), n - 2)
        fs = s - k
        t_lim = self.t_max[k] + fs * (self.t_max[k + 1] - self.t_max[k])
        f = abs(torque) / t_lim if t_lim > 0 else 0.0
        if f > 1.0:
            f, status = 1.0, max(status, 1)
        c = f * (self.i_d.shape[1] - 1)
        j = min(int(c), self.i_d.shape[1] - 2)
        fc = c - j

        def bil(a):
            lo = a[k, j] + fc * (a[k, j + 1] - a[k, j])
            hi = a[k + 1, j] + fc * (a[k + 1, j + 1] - a[k + 1, j])
            return lo + fs * (hi - lo)

        i_q = bil(self.i_q)
        return bil(self.i_d), (-i_q if torque < 0 else i_q), status


def envelope_table(motor, drive, n_speed: int = N_SPEED, n_torque: int = N_TORQUE):
    """The reference table of ``motor`` on ``drive`` (module docstring); None
    when the motor has no current limit (no envelope). Rows are computed in
    float64 and rounded to float32, as the header stores them."""
    # lazy: scipy.optimize (the header without a table); the saturated envelope
    # for a saturated motor
    from ..plant import OperatingEnvelope, envelope_of

    v_circle = drive.max_voltage(motor.convention)
    try:
        env = envelope_of(motor, v_max=(1.0 - OperatingEnvelope.HEADROOM) * v_circle)
    except SpecError:
        return None
    top = drive.max_speed if drive.max_speed else 2.0 * env.base_speed()

    def fits(w):
        try:
            return env.max_torque_point(w).torque > 0.0
        except SpecError:
            return False

    if not fits(top):  # the highest speed with a positive torque limit (bisection, 1e-4)
        lo, hi = 0.0, top
        while hi - lo > 1e-4 * top:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if fits(mid) else (lo, mid)
        top = lo
    step = float(np.float32(top / (n_speed - 1)))
    t_max = np.zeros(n_speed)
    i_d = np.zeros((n_speed, n_torque))
    i_q = np.zeros((n_speed, n_torque))
    for k in range(n_speed):
        w = k * step
        lim = env.max_torque_point(w)
        t_max[k] = lim.torque
        for j in range(n_torque):
            op = env.operating_point(t_max[k] * j / (n_torque - 1), w, lim)
            i_d[k, j], i_q[k, j] = op.i_d, op.i_q
    f32 = lambda a: a.astype(np.float32).astype(float)  # noqa: E731
    src = ({} if motor.magnetics is None else
           {"source": "toolbox.plant.SaturatedEnvelope, the motor's magnetic model"})
    return EnvelopeTable(step, f32(t_max), f32(i_d), f32(i_q), env.V, env.I, **src)


def envelope_section(table: EnvelopeTable | None, N: str, P: str, why: str = "") -> list[str]:
    """The header's envelope block: the tables and ``<N>_envelope_ref``."""
    if table is None:
        return [f"/* Operating envelope: not exported ({why or 'no current limit'}). */", ""]
    ns, nt = table.i_d.shape
    key = "motor"
    L = [f"/* Operating envelope ({table.source}):",
         " * current references for a torque at a speed: MTPA below base speed, field",
         " * weakening above, the torque limit where the request exceeds it; voltage",
         f" * limit {table.v_max:.6g} V (the drive's circle less 5 % for the loop), current",
         f" * limit {table.i_max:.6g} A. Table of {ns} speeds (0 .. {table.top_speed:.6g} rad/s",
         f" * mechanical) x {nt} torques (0 .. the limit at that speed), interpolated linearly",
         " * in |speed| and in the torque's fraction of the limit; a negative torque mirrors",
         " * i_q. Memory: (N_SPEED + 2 N_SPEED N_TORQUE) x 4 = "
         f"{4 * (ns + 2 * ns * nt)} bytes of constants. */",
         f"#define {P}ENV_N_SPEED {ns}",
         f"#define {P}ENV_N_TORQUE {nt}",
         f"#define {P}ENV_SPEED_STEP {_f(table.speed_step, key, 'envelope speed step')} "
         "/* rad/s between rows */",
         f"static const float {N}_env_t_max[{ns}] = {{"
         + ", ".join(_f(v, key, "envelope torque limit") for v in table.t_max) + "};"]
    for name, arr in (("i_d", table.i_d), ("i_q", table.i_q)):
        L.append(f"static const float {N}_env_{name}[{ns}][{nt}] = {{")
        for k in range(ns):
            L.append("    {" + ", ".join(_f(v, key, f"envelope {name}") for v in arr[k]) + "},")
        L.append("};")
    L += ["/* torque (N m), omega_m (mechanical rad/s) -> *i_d_ref, *i_q_ref (A); returns 0,",
          " * 1 (torque clamped to the limit at that speed) or 2 (|omega_m| beyond the",
          " * table: its last row used). The Python mirror is",
          " * toolbox.export._envelope_table.EnvelopeTable.reference. */",
          f"static inline int {N}_envelope_ref(float torque, float omega_m, float *i_d_ref, "
          "float *i_q_ref)",
          "{",
          "    int status = 0;",
          f"    float s = (omega_m < 0.0f ? -omega_m : omega_m) / {P}ENV_SPEED_STEP;",
          f"    if (!(s <= (float)({P}ENV_N_SPEED - 1))) {{ s = (float)({P}ENV_N_SPEED - 1); "
          "status = 2; }",
          "    int k = (int)s;",
          f"    if (k > {P}ENV_N_SPEED - 2) {{ k = {P}ENV_N_SPEED - 2; }}",
          "    const float fs = s - (float)k;",
          f"    const float t_lim = {N}_env_t_max[k] + fs * ({N}_env_t_max[k + 1] - "
          f"{N}_env_t_max[k]);",
          "    const float ta = torque < 0.0f ? -torque : torque;",
          "    float f = t_lim > 0.0f ? ta / t_lim : 0.0f;",
          "    if (f > 1.0f) { f = 1.0f; if (status == 0) { status = 1; } }",
          f"    const float c = f * (float)({P}ENV_N_TORQUE - 1);",
          "    int j = (int)c;",
          f"    if (j > {P}ENV_N_TORQUE - 2) {{ j = {P}ENV_N_TORQUE - 2; }}",
          "    const float fc = c - (float)j;",
          f"    const float d_lo = {N}_env_i_d[k][j] + fc * ({N}_env_i_d[k][j + 1] - {N}_env_i_d[k][j]);",
          f"    const float d_hi = {N}_env_i_d[k + 1][j] + fc * ({N}_env_i_d[k + 1][j + 1] - "
          f"{N}_env_i_d[k + 1][j]);",
          f"    const float q_lo = {N}_env_i_q[k][j] + fc * ({N}_env_i_q[k][j + 1] - {N}_env_i_q[k][j]);",
          f"    const float q_hi = {N}_env_i_q[k + 1][j] + fc * ({N}_env_i_q[k + 1][j + 1] - "
          f"{N}_env_i_q[k + 1][j]);",
          "    const float iq = q_lo + fs * (q_hi - q_lo);",
          "    *i_d_ref = d_lo + fs * (d_hi - d_lo);",
          "    *i_q_ref = torque < 0.0f ? -iq : iq;",
          "    return status;",
          "}",
          ""]
    return L
