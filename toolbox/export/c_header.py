"""Firmware export: the controller artifact as a C99 header (``controller.h``).

The header is self-contained (header-only, include guards, no dynamic
memory, only ``sqrtf`` from libm; ``sinf``/``cosf`` too for the hexagon) and
implements the whole current-control law of the artifact in one
``static inline`` step function:

1. per axis, the discrete two-input law ``[i_ref, i_meas] -> v`` of
   :class:`toolbox.artifact.AxisController` (``law``), realised minimally
   with round-off treated as zero (:mod:`toolbox.export._minimal`), as CMSIS-DSP style
   second-order sections when the law is one-degree-of-freedom
   (``v = K (i_ref - i_meas)``), else in state-space form;
2. the decoupling of :class:`toolbox.artifact.Decoupling`:
   ``v_d += -cross w_m Lq_c i_q``, ``v_q += cross w_m Ld_c i_d + emf w_m flux_c``
   with ``w_m = pole_pairs Omega_m``;
3. the voltage limit of ``drive.voltage_limit``, radial scaling as in the
   toolbox simulator (:mod:`toolbox.sim._kernel`): the circle of radius
   ``drive.max_voltage(convention)``, or the SVM hexagon with that apothem
   seen at the electrical angle ``theta_e + w_e Ts (delay + 1/2)`` (the header
   then takes the input ``theta_e``);
   With ``drive.voltage_priority = "d_axis"`` the limit keeps ``v_d``
   (clamped to the limit's d extent times the guard ``d_priority_cap`` that
   leaves ``v_q`` the speed voltage ``w (Ld_c i_d + psi_c)``) and gives ``v_q`` the rest instead
   (``sign(v_q) sqrt(V_MAX^2 - v_d^2)`` on the circle, the hexagon's chord at
   that ``v_d``), as the simulator's ``_voltage_limit``;
4. back-calculation anti-windup ``x += aw (v_sat - v_unsat)`` with the
   artifact's vector mapped into the executed coordinates;
5. (beside the law) the operating envelope's current references as a table
   over speed and torque and ``<p>envelope_ref``
   (:mod:`toolbox.export._envelope_table`; 1 564 bytes of constants).

Faults (float path): a non-finite input, or a non-finite result, repeats the
last good output, leaves the state unchanged and sets ``out.status`` (1 and 2;
0 otherwise). :class:`ReferenceLaw` is the same law in double precision.

Every emitted constant is range-checked first (float32 range and normal
numbers, integer ranges of C); out of range, the export is refused with
:class:`toolbox.errors.ExportRefused` naming the spec key responsible
(``drive.vdc``, ``motor.R``, ...), so the header never holds ``inff``/``nan``.

A fixed-point variant (``#define CCT_FIXED_POINT`` before including) adds
``cct_step_q31`` with Q31 signals and int64 accumulators; see
:mod:`toolbox.export._fixed` for the scaling rules.

Every identifier carries the prefix (``prefix=``, default ``cct_``: guard
``CCT_CONTROLLER_H``, switch ``CCT_FIXED_POINT``). The voltage limit in use is
set at run time from the measured bus (``<p>set_vdc``); the delay
compensation is applied in ``<p>step`` (outputs ``v_d_comp``, ``v_q_comp``);
a usage example closes the header under ``#if 0``.

STM32 MCSDK-style (``<P>MCSDK``) and TI IQmath-style (``<P>IQMATH``) integer
variants of a one-degree-of-freedom PI law: :mod:`toolbox.export._vendor`
(templates/vendor.c.j2).

Method ``fcs_mpc`` exports its predictive switching law instead (paper 002
criterion (23) over the 8 inverter states with the switching penalty, one
forward-Euler prediction, the one-period delay handled as the simulator's
``_fcs_choice``; templates/fcs.c.j2), float only. Method ``cv`` exports its
complex-vector law, gains computed each period at the measured speed as the
simulator's ``_kernel_cv`` (:mod:`toolbox.export._cv_section`,
templates/cv_top.c.j2, cv.c.j2), float only.

Exportability rules (:func:`check_exportable`) -- a controller is refused with
:class:`toolbox.errors.ExportRefused` (key ``controller.<method>``, the
message names the axis) when:

* **unstable**: a pole of the discrete law has ``|z| >= 1``, other than one
  simple integrator exactly at ``z = 1`` (``|z - 1| <= 1e-9``) per axis;
* **Nyquist ringing**: a pole with ``Re z < 0`` and ``|z| > 0.9`` (the Tustin
  image of a continuous pole faster than ~12 x the Nyquist frequency) that
  no zero cancels to within 1 % of its distance to the unit circle (the pair
  then changes |K| by at most 1 % at any frequency, the rule of
  :func:`toolbox.design._hinf_gamma.effective_poles` transposed to z);
* **coefficient dynamic range** of one coefficient set (SOS stage or state
  row) above ``2**30`` (beyond Q31 resolution even with per-set scaling);
* **rounding sensitivity**: rounding the executed coefficients to float32
  (or to Q31 for the fixed-point variant) moves a pole by more than
  ``1 % (1 - |p|) + Ts * 0.01 rad/s`` or destabilises it. The absolute term
  is a 0.01 rad/s shift of the pole's continuous equivalent, immaterial for
  current loops and the only fair yardstick for near-integrators (paper 003's
  controller pole at 0.0117 rad/s lies 1.2e-6 inside the unit circle).

The fixed-point variant is additionally refused (the header then carries an
``#error`` under ``CCT_FIXED_POINT``) when no finite state bound exists, when
one of its constants is out of range, for ``voltage_limit = "hexagon"`` and
for ``voltage_priority = "d_axis"`` (not implemented in Q31, MCSDK, IQmath).

This module is the entry point that writes the header (:func:`write_header`:
the opening comment, the ``#define`` block, the template environment, the
predictive law's header and the usage example); the parts live in private
modules of the package, re-exported here: :mod:`toolbox.export._check`
(:func:`check_exportable`, :class:`ExportCheck`), :mod:`toolbox.export._reference`
(:class:`ReferenceLaw`, :func:`reference_law`), :mod:`toolbox.export._format`
(comment sanitising, range-checked literals), :mod:`toolbox.export._placement`,
:mod:`toolbox.export._plausible`, :mod:`toolbox.export._informational` and the
sections :mod:`toolbox.export._float_section`, :mod:`toolbox.export._fixed_section`,
:mod:`toolbox.export._vendor_section`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from ..errors import CctError, ExportRefused, SpecError
from ._check import (AXES, CANCEL_TOL, DYNAMIC_RANGE, HORIZON, INTEGRATOR_TOL,  # noqa: F401
                     POLE_ABS_RAD_S, POLE_REL_TOL, PRIORITIES, RING_RADIUS, ExportCheck,
                     _law_key, _motor_drive, check_exportable, check_fixed, minimal_laws,
                     realisations)
from ._fixed_section import _fixed_section
from ._float_section import _float_section, preset_coefficients  # noqa: F401
from ._format import (C_INT32_MAX, C_INT_MAX, F32_MAX, F32_TINY, _f, _int,  # noqa: F401
                      _Text, sanitise_comment)
from ._informational import PI_METHODS, _informational_pi_gains  # noqa: F401
from ._placement import (Q31_MAX_PLACEMENT_ANGLE, _delay_comp_time,  # noqa: F401
                         _placement_convention)
from ._plausible import (PLAUSIBLE_MARGIN, VDC_MAX_PER_NOMINAL,  # noqa: F401
                         VDC_MIN_PER_NOMINAL, _plausible_context, plausibility_limits)
from ._reference import ReferenceLaw, d_priority_limit, reference_law  # noqa: F401
from ._vendor_section import _vendor_section, vendor_plan  # noqa: F401
from ..spec import inverter_radii
from .._cache import template_bytecode_cache
from ._cv_section import write_cv_header
from ._envelope_table import envelope_section, envelope_table

__all__ = ["write_header", "check_exportable", "ExportCheck", "sanitise_comment",
           "realisations", "reference_law", "ReferenceLaw", "check_fixed", "INTEGRATOR_TOL", "RING_RADIUS",
           "DYNAMIC_RANGE", "prefix_name", "example_source"]


# ---------------------------------------------------------------------------
# C text
# ---------------------------------------------------------------------------
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,30}")  # fullmatch (no trailing newline)
TEMPLATES = Path(__file__).parent / "templates"
_ENV = None


def _provenance(artifact, title: str) -> dict:
    """The provenance strings of the header comment (every user string
    sanitised), for the ``provenance`` macro of ``templates/common.c.j2``."""
    prov = artifact.provenance or {}
    return {"title": sanitise_comment(title), "method": sanitise_comment(artifact.method),
            **{k: sanitise_comment(prov.get(k, "unknown"))
               for k in ("version", "spec_sha256", "created")},
            "magnetics_sha256": (sanitise_comment(prov["magnetics_sha256"])
                                 if prov.get("magnetics_sha256") else None),
            "law_sha256": artifact.law_sha256()}


def _header_top(t: _Text, artifact, motor, drive, N: str, check: ExportCheck,
                title: str) -> None:
    """The opening comment of a linear law's header (``templates/top.c.j2``)."""
    eqs = (artifact.provenance or {}).get("equations")
    t.lines.extend(_render(
        "top.c.j2", prov=_provenance(artifact, title), N=N, U=N.upper(),
        equations=sanitise_comment('; '.join(map(str, eqs)), 400) if eqs else None,
        hexagon=check.limit == "hexagon", comp=_delay_comp_time(artifact) is not None,
        d_priority=check.priority == "d_axis",
        warnings=[(ax, f"{check.saturated_radius[ax]:.9g}") for ax in check.marginal_antiwindup]))


def _defines(t: _Text, artifact, motor, drive, P: str, check: ExportCheck) -> None:
    """The ``#define`` block (``templates/defines.c.j2``); every number is
    formatted and range-checked here, in the order of the lines."""
    dec = artifact.decoupling
    ts_ = _f(artifact.sample_time, "drive.sample_time", "controller period SAMPLE_TIME")
    nd_ = _int(artifact.delay_samples, "drive.delay_samples", "DELAY_SAMPLES", 0)
    vmax_ = _f(check.v_max, "drive.vdc", "voltage limit V_MAX")
    if check.v_max ** 2 > F32_MAX:
        # the step function compares |v|^2 with V_MAX^2 in float
        raise ExportRefused("drive.vdc", f"a voltage limit whose square fits float32 "
                            f"(V_MAX <= {math.sqrt(F32_MAX):.3g} V)", check.v_max)
    per_vdc = (_f(check.v_max / drive.vdc, 'drive.vdc', 'V_MAX_PER_VDC')
               if drive is not None and drive.vdc > 0 else None)
    mot = None
    if motor is not None:
        mot = {"convention": sanitise_comment(motor.convention),
               "R": _f(motor.R, 'motor.R', 'MOTOR_R'),
               "Ld": _f(motor.Ld, 'motor.Ld', 'MOTOR_LD'),
               "Lq": _f(motor.Lq, 'motor.Lq', 'MOTOR_LQ'),
               "flux": _f(motor.flux, 'motor.flux', 'MOTOR_FLUX'),
               "pole_pairs": _int(motor.pole_pairs, 'motor.pole_pairs', 'MOTOR_POLE_PAIRS', 1),
               "J": _f(motor.J, 'motor.J', 'MOTOR_J'),
               "friction": _f(motor.friction, 'motor.friction', 'MOTOR_FRICTION')}
        for name in ("max_current", "rated_current", "rated_speed"):
            v = getattr(motor, name)
            mot[name] = _f(v, f"motor.{name}", f"MOTOR_{name.upper()}") if v else None
    drv = None
    if drive is not None:
        fsw = drive.switching_frequency
        drv = {"vdc": _f(drive.vdc, 'drive.vdc', 'DRIVE_VDC'),
               "switching_frequency": (_f(fsw, 'drive.switching_frequency',
                                          'DRIVE_SWITCHING_FREQUENCY') if fsw else None)}
    dec_ = {"cross": int(bool(dec.cross)), "emf": int(bool(dec.emf)),
            "Ld": _f(dec.Ld_c, 'motor.Ld', 'decoupling DEC_LD'),
            "Lq": _f(dec.Lq_c, 'motor.Lq', 'decoupling DEC_LQ'),
            "flux": _f(dec.flux_c, 'motor.flux', 'decoupling DEC_FLUX'),
            "pole_pairs": _int(dec.pole_pairs, 'motor.pole_pairs', 'POLE_PAIRS', 1)}
    # the dq model that predicts a replaced current sample: the motor's data, else the law's
    src = motor
    pred = {k: _f(v, f"motor.{k}", f"PRED_{k.upper()}") for k, v in (
        ("R", src.R if src else dec.R_c), ("Ld", src.Ld if src else dec.Ld_c),
        ("Lq", src.Lq if src else dec.Lq_c), ("flux", src.flux if src else dec.flux_c))}
    pred["what"] = "motor data" if src else "the law's decoupling model"
    t_comp = artifact.decoupling.delay_compensation_time
    comp = {"time": _f(t_comp, 'drive.angle_compensation', 'DELAY_COMP_TIME'),
            "periods": f"{t_comp / artifact.sample_time:g}",
            "convention": _placement_convention(artifact)}
    pi = [{"axis": ax, "kp": f"{kp:.9g}", "ki": f"{ki:.9g}",
           "ki_ts": f"{ki * artifact.sample_time:.9g}",
           "ti": f"{kp / ki:.9g}" if kp and ki else None}
          for ax, kp, ki in _informational_pi_gains(artifact)]
    lines = _render("defines.c.j2", P=P, p=P.lower(), ts=ts_, nd=nd_, vmax=vmax_,
                    what="hexagon apothem" if check.limit == "hexagon" else "circle radius",
                    vmax_per_vdc=per_vdc, motor=mot, drive=drv, dec=dec_, comp=comp, pred=pred,
                    method=artifact.method, pi=pi)
    t.lines.extend(lines[:-1] if lines and lines[-1] == "" else lines)


def _render(template: str, **context: Any) -> list[str]:
    """Lines of ``templates/<template>`` rendered with ``context``."""
    return _environment().get_template(template).render(**context).split("\n")


def _environment():
    """The jinja2 environment of the C templates (no autoescape: C, not HTML;
    every user string is sanitised by :func:`sanitise_comment` before)."""
    global _ENV
    if _ENV is None:
        import jinja2  # lazy: jinja2 + markupsafe, 21 modules

        _ENV = jinja2.Environment(
            loader=jinja2.FileSystemLoader(str(TEMPLATES)), autoescape=False,
            bytecode_cache=template_bytecode_cache(__file__),
            trim_blocks=True, lstrip_blocks=True, undefined=jinja2.StrictUndefined)
    return _ENV


def fcs_r_hex_per_vdc(convention: str) -> float:
    """Length of an active inverter vector per volt of bus (the hexagon's
    vertex radius, :func:`toolbox.spec.inverter_radii`)."""
    return inverter_radii(1.0, convention)[0]


def _write_fcs_header(artifact, motor, drive, name: str, title: str | None,
                      example: bool) -> str:
    """controller.h of method ``fcs_mpc``: the predictive switching law of paper
    002 criterion (23) as the simulator runs it (``toolbox.sim._kernel._fcs_choice``),
    float only."""
    if drive is None:
        raise ExportRefused("drive", "drive data (vdc) for the inverter vectors",
                            hint="pass drive= or keep [drive] in the artifact's spec")
    conv = motor.convention if motor is not None else "amplitude"
    N = name.lower()
    P = name.upper() + "_"
    guard = f"{P}CONTROLLER_H"
    if title is None:
        title = (artifact.spec or {}).get("title", "")
    fcs = artifact.fcs
    dec = artifact.decoupling
    key = _law_key(artifact)
    predict = int(artifact.delay_samples) >= 1
    k_hex = fcs_r_hex_per_vdc(conv)
    t = _Text()
    d = {"ts": _f(artifact.sample_time, 'drive.sample_time', 'SAMPLE_TIME'),
         "nd": _int(artifact.delay_samples, 'drive.delay_samples', 'DELAY_SAMPLES', 0),
         "vdc": _f(drive.vdc, 'drive.vdc', 'DRIVE_VDC'),
         "r_hex_per_vdc": _f(k_hex, 'drive.vdc', 'R_HEX_PER_VDC'),
         "convention": sanitise_comment(conv),
         "r_hex": _f(k_hex * drive.vdc, 'drive.vdc', 'R_HEX'),
         "R": _f(dec.R_c, 'motor.R', 'DEC_R'), "Ld": _f(dec.Ld_c, 'motor.Ld', 'DEC_LD'),
         "Lq": _f(dec.Lq_c, 'motor.Lq', 'DEC_LQ'), "flux": _f(dec.flux_c, 'motor.flux', 'DEC_FLUX'),
         "pole_pairs": _int(dec.pole_pairs, 'motor.pole_pairs', 'POLE_PAIRS', 1),
         "alpha": _f(fcs.alpha, key + '.alpha', 'FCS_ALPHA'),
         "beta": _f(fcs.beta, key + '.beta', 'FCS_BETA'),
         "gamma": _f(fcs.gamma, key + '.gamma', 'FCS_GAMMA')}
    t.lines.extend(_render("fcs_top.c.j2", prov=_provenance(artifact, title), N=N, P=P,
                           U=N.upper(), guard=guard, delay=int(artifact.delay_samples), d=d))
    t("")
    v_hex = k_hex * drive.vdc * math.sqrt(3.0) / 2.0        # the hexagon's apothem
    t.lines.extend(_render("fcs.c.j2", N=N, P=P, U=N.upper(), predict=predict,
                           plausible=_plausible_context(artifact, motor, drive, v_hex)))
    if example:
        t("")
        _example(t, N, P, fcs=True)
    t("")
    t(f"#endif /* {guard} */")
    return t.text()


EXAMPLE_BEGIN = "EXAMPLE main.c BEGIN"
EXAMPLE_END = "EXAMPLE main.c END"


def example_source(header: str) -> str:
    """The usage example written at the end of a header (the C text between
    the ``EXAMPLE main.c BEGIN`` and ``END`` lines), to compile as ``main.c``."""
    lines = header.splitlines()
    i = next(k for k, ln in enumerate(lines) if EXAMPLE_BEGIN in ln)
    j = next(k for k, ln in enumerate(lines) if EXAMPLE_END in ln)
    return "\n".join(lines[i + 1:j]) + "\n"


def _example(t: _Text, N: str, P: str, *, hexagon: bool = False, fcs: bool = False) -> None:
    """A compilable main.c, inside ``#if 0`` (no ``/*`` in it): ``templates/example.c.j2``,
    the predictive switching law's (``fcs``) or the linear law's."""
    t.lines.extend(_render("example.c.j2", N=N, P=P, U=N.upper(), hexagon=hexagon, fcs=fcs,
                           begin=EXAMPLE_BEGIN, end=EXAMPLE_END))


def write_header(artifact, motor=None, drive=None, *, name: str = "cct",
                 prefix: str | None = None, title: str | None = None,
                 source: str | None = None, example: bool = True) -> str:
    """The C99 header text of a controller artifact.

    Parameters
    ----------
    artifact : ControllerArtifact
        The designed controller (checked by :func:`check_exportable` first).
    motor, drive : Motor, Drive, optional
        Motor and drive data for the ``#define`` block and the voltage limit
        (default: read from ``artifact.spec``).
    name : str
        Prefix of every C identifier (``<name>_step``, ``<NAME>_V_MAX``); a C
        identifier of at most 31 characters.
    prefix : str, optional
        The C prefix (``cct export --prefix``, ``[export] prefix``), ``name``
        with its underscore:
        ``"motor1_"`` gives ``motor1_step``, ``MOTOR1_V_MAX``, the guard
        ``MOTOR1_CONTROLLER_H`` and the switch ``MOTOR1_FIXED_POINT``; a
        trailing underscore is added when missing (``"motor1"`` is the same).
        It must start with a letter; it overrides ``name``. Two headers in one
        program need prefixes that differ in upper case.
    example : bool
        Append the usage example (init, bus-voltage update, per-period call,
        fault handling) as a comment at the end of the header.
    title : str, optional
        Title for the provenance comment (default: ``artifact.spec["title"]``);
        sanitised by :func:`sanitise_comment`.
    source : str, optional
        The design file the artifact came from (``DIR/controller.json``);
        every refusal names it.

    Returns
    -------
    str
        The header text (the CLI writes it atomically).

    Raises
    ------
    ExportRefused
        Refused controller (see :func:`check_exportable`) or a constant out of
        range (float32, C integer ranges), naming the spec key; with the
        ``source`` file when given.
    SpecError
        Bad ``name``.
    """
    try:
        if prefix is not None:
            name = prefix_name(prefix)
        return _write_header(artifact, motor, drive, name, title, example)
    except CctError as err:
        if source and not err.file:
            raise err.with_file(str(source)) from None
        raise


#: Used with fullmatch: ``$`` of re.match also matches before a trailing newline.
PREFIX_RE = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,30}")


def prefix_name(prefix: Any, key: str = "export.prefix") -> str:
    """The identifier stem of a C prefix: ``"motor1_"`` and ``"motor1"`` -> ``"motor1"``.

    Parameters
    ----------
    prefix : str
        A C identifier starting with a letter, at most 31 characters, with
        or without its trailing underscore.
    key : str
        The key named in the error.

    Raises
    ------
    SpecError
        Not such an identifier.
    """
    if not isinstance(prefix, str) or not PREFIX_RE.fullmatch(prefix):
        raise SpecError(key, "a C identifier prefix: a letter, then letters, digits or _ "
                        "(at most 31 characters), e.g. \"motor1_\"", prefix)
    stem = prefix[:-1] if prefix.endswith("_") else prefix
    if not stem:
        raise SpecError(key, "a prefix with a letter before the underscore", prefix)
    return stem


def _write_header(artifact, motor, drive, name: str, title: str | None,
                  example: bool = True) -> str:
    if not isinstance(name, str) or not _IDENT.fullmatch(name):
        raise SpecError("export.name", "a C identifier of at most 31 characters", name)
    motor, drive = _motor_drive(artifact, motor, drive)
    if artifact.method == "fcs_mpc":
        return _write_fcs_header(artifact, motor, drive, name, title, example)
    if artifact.cv is not None:
        if title is None:
            title = (artifact.spec or {}).get("title", "")
        return write_cv_header(artifact, motor, drive, name, title, render=_render,
                               provenance=_provenance(artifact, title),
                               example=_example if example else None)
    check = check_exportable(artifact, motor, drive)
    N = name.lower()
    P = name.upper() + "_"
    if title is None:
        title = (artifact.spec or {}).get("title", "")
    guard = f"{P}CONTROLLER_H"
    t = _Text()
    _header_top(t, artifact, motor, drive, N, check, title)
    t(f"#ifndef {guard}")
    t(f"#define {guard}")
    t("")
    trig = check.limit == "hexagon" or _delay_comp_time(artifact) is not None
    t("#include <math.h> /* sqrtf" + (", sinf, cosf" if trig else "") + " */")
    t("#include <stdint.h> /* uint32_t */")
    t("")
    _defines(t, artifact, motor, drive, P, check)
    t("")
    for ax in AXES:
        r = check.realisations[ax]
        if r.form == "sos":
            t(f"#define {P}{ax.upper()}_GAIN {_f(r.gain, _law_key(artifact), f'{ax}-axis SOS gain')} /* {ax} axis SOS output gain, V/A */")
            t(f"#define {P}{ax.upper()}_NUM_STAGES {r.sos.shape[0]}")
    t("")
    _float_section(t, check.realisations, N, P, _law_key(artifact), check.limit == "hexagon",
                   _delay_comp_time(artifact) is not None,
                   _plausible_context(artifact, motor, drive, check.v_max),
                   motor.convention if motor is not None else "amplitude",
                   d_priority=check.priority == "d_axis")
    if _delay_comp_time(artifact) is not None:
        t.lines.extend(_render("placement.c.j2", N=N, P=P))
    _fixed_section(t, check, N, P, artifact, drive)
    t("")
    _vendor_section(t, artifact, motor, drive, check, N, P)
    t("")
    t.lines.extend(envelope_section(envelope_table(motor, drive) if motor is not None
                                    and drive is not None else None, N, P,
                                    "no motor and drive data"))
    if example:
        _example(t, N, P, hexagon=check.limit == "hexagon")
        t("")
    t(f"#endif /* {guard} */")
    return t.text()
