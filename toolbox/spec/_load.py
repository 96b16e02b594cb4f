"""TOML spec files -> validated :class:`~toolbox.spec.Spec` objects.

Values are taken only as TOML gives them (``tomllib``); nothing is evaluated.
Every error is a :class:`~toolbox.errors.SpecError` naming the file, the key
path, what was expected and what was found.
"""

from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from .._io import check_data_depth, check_text_depth, read_limited
from ..errors import SpecError
from ._campaign import read_campaign
from ._catalog import CATALOG
from ._datasheet import (catalog_kept, convert_scenario, relocate, reported_keys,
                         resolve_drive, resolve_motor)
from ._bounds import (check_drive, check_motor, check_motor_drive, check_plant_variant,
                      check_requirement, check_scenario_count, check_speed, check_work)
from ._fields import Collector, Table, check_keys, did_you_mean
from ._method_units import convert_method_units
from ._methods import read_method_cfg
from ._scenario import Scenario
from ._model import (DRIFT_FACTOR_RANGE, DRIFT_PARAMETERS, METHODS, REQUIREMENT_KEYS,
                     ControllerChoice, Drive, Motor, Requirements, Spec)
from ._overrides import apply_overrides, blame_overrides

__all__ = ["load_spec", "spec_from_dict", "motor_from_dict", "drive_from_dict"]

TOP_KEYS = ("title", "motor", "drive", "controller", "requirements", "scenario", "export",
            "campaign")
EXPORT_KEYS = ("prefix",)
#: a C identifier prefix (letter first, at most 31 characters); the export
#: (toolbox.export.prefix_name) applies the same rule. Used with fullmatch:
#: ``$`` of re.match also matches before a trailing newline ("m\n").
_C_PREFIX = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,30}")
MOTOR_KEYS = ("catalog", "R", "Ld", "Lq", "flux", "pole_pairs", "J", "friction",
              "convention", "rated_current", "max_current", "rated_speed",
              # saturated motors (toolbox/spec/_flux_map.py)
              "flux_map", "saturation",
              # datasheet forms (toolbox/spec/_datasheet.py)
              "R_ll", "L_ll", "ke_ll_peak", "ke_ll_rms", "kt_peak", "kt_rms",
              "rated_current_rms", "max_current_rms")
DRIVE_KEYS = ("vdc", "sample_time", "delay_samples", "switching_frequency",
              "voltage_limit", "max_speed", "sample_frequency", "hold_frame",
              "angle_compensation", "voltage_priority")


def load_spec(path: str | Path, overrides: Sequence[tuple[str, str]] = ()) -> Spec:
    """Read and validate a spec file.

    Parameters
    ----------
    path : str or Path
        TOML file (format: README.md "Spec files", toolbox/ARCHITECTURE.md).
    overrides : sequence of (option, "key.path=value"), optional
        Values replacing those of the file before validation, in order
        (``cct design --set``/``--method``, :mod:`toolbox.spec._overrides`);
        an error on an overridden key names the override.

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        Unreadable file, TOML syntax error, or any invalid value; the message
        names the file and the key.
    """
    name = str(path)
    raw = read_limited(path, SpecError, what="spec file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SpecError("", "a UTF-8 text file", "undecodable bytes", file=name) from None
    check_text_depth(text, SpecError, file=name)  # tomllib recurses: bound depth first
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SpecError("", "valid TOML", str(err), file=name) from None
    if not overrides:
        return spec_from_dict(data, file=name)

    try:
        data = apply_overrides(data, overrides)
    except SpecError as err:
        raise err.with_file(name) from None
    try:
        return spec_from_dict(data, file=name)
    except SpecError as err:
        raise blame_overrides(err, overrides) from None


def spec_from_dict(data: Mapping[str, Any], file: str | None = None) -> Spec:
    """Validate a spec given as plain data (the parsed TOML).

    Parameters
    ----------
    data : Mapping
        The spec tables.
    file : str, optional
        Where the data came from (named in error messages).

    Examples
    --------
    >>> spec = spec_from_dict({"motor": {"catalog": "azaiz2007"},
    ...                        "drive": {"vdc": 150, "sample_time": 1e-4},
    ...                        "controller": {"method": "pi"}})
    >>> spec.motor.Lq
    0.0028
    """
    try:
        check_data_depth(data, SpecError)  # deepcopy and the readers recurse
        return _spec(data, file)
    except SpecError as err:
        raise (err.with_file(file) if file else err) from None


def _spec(data: Mapping[str, Any], file: str | None) -> Spec:
    """Read every section, collecting independent errors so that one run
    reports all of them (a section that depends on another is read only
    when that one is valid)."""
    top = Table(data, "", TOP_KEYS)
    errors = Collector()
    title = ""
    with errors.check():
        title = top.string("title", "")
    motor = motor_raw = drive = controller = None
    conversions: list = []
    with errors.check():
        motor, motor_raw, motor_log = _motor_logged(
            top.raw("motor"), Path(file).parent if file else None)
        conversions += motor_log
    with errors.check():
        drive, drive_log = _drive_logged(top.raw("drive"))
        conversions += drive_log
    if motor is not None:
        check_motor(motor, errors)
    if drive is not None:
        check_drive(drive, errors)
    if motor is not None and drive is not None and not errors.failed:
        check_motor_drive(motor, drive, errors)
    if not errors.failed:  # method parameters are read against a plausible motor
        with errors.check():
            controller = _controller(top.raw("controller"), motor, drive)
    else:  # the method's table is still checked, so that one run reports it too
        drive_ok = drive is not None and not any(
            e.key.startswith("drive.") for e in errors.errors)
        for err in _controller_alone(top.raw("controller"), drive if drive_ok else None):
            errors.add(err)
    requirements = None
    with errors.check():
        requirements = _requirements(top.raw("requirements"))
    export_prefix = "cct_"
    with errors.check():
        export_prefix = _export_prefix(top.raw("export", {}))
    scenarios: tuple = ()
    if drive is not None:  # read even when the motor or controller failed: all errors at once
        method = controller.method if controller is not None else _known_method(
            top.raw("controller"))
        with errors.check():
            scenarios = _scenarios(top.raw("scenario", []), drive, method, errors,
                                   _convention(top.raw("motor")))
        check_work(scenarios, drive.sample_time, errors)
        if motor is not None and not errors.failed:  # against a plausible motor and drive
            _check_scenario_plants(scenarios, motor, drive, errors)
    campaign = None
    if top.has("campaign"):
        with errors.check():
            campaign = read_campaign(top.raw("campaign"))
            _check_campaign_scenarios(campaign, scenarios)
    # a range error on a derived value names the key the user wrote (R_ll, not R)
    errors.errors = [relocate(e, conversions) for e in errors.errors]
    errors.raise_if_any()
    raw = copy.deepcopy(dict(data))
    raw["motor"] = motor_raw
    return Spec(title=title, motor=motor, drive=drive, controller=controller,
                requirements=requirements, scenarios=scenarios, raw=raw, source=file,
                conversions=tuple(conversions), export_prefix=export_prefix,
                campaign=campaign)


def _check_campaign_scenarios(campaign, scenarios: tuple) -> None:
    """``campaign.scenarios`` names scenarios of the spec (``name``, else ``kind``)."""
    names = [s.name or s.kind for s in scenarios]
    for name in campaign.scenarios:
        if name not in names:
            raise SpecError("campaign.scenarios", "names of [[scenario]] tables ("
                            + (", ".join(f'"{n}"' for n in names) or "none given") + ")",
                            name, hint=did_you_mean(name, names))


def _collect(errors: Collector, read: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``read(*args, **kwargs)``, or None with its SpecError recorded."""
    with errors.check():
        try:
            return read(*args, **kwargs)
        except _AlreadyReported:  # its message is in ``errors`` already
            return None
    return None


class _Unreported(Table):
    """A table whose already-reported keys read as None (one message per key:
    a failed unit conversion is not also "expected a number")."""

    def __init__(self, data: Any, prefix: str, reported: set[str]) -> None:
        super().__init__(data, prefix)
        self.reported = reported

    def _get(self, name: str, default: Any, expected: str) -> Any:
        if name in self.reported:
            raise _AlreadyReported()
        return super()._get(name, default, expected)


def _lenient_table(value: Any, prefix: str, allowed: Sequence[str], errors: Collector) -> Table:
    """``Table(value, prefix, allowed)`` that records each unknown key in
    ``errors`` and goes on reading the known ones (every error of the table in
    one run, not only the first)."""
    if not isinstance(value, Mapping):
        return Table(value, prefix, allowed)  # not a table: nothing else to read
    known = {}
    for key, item in value.items():
        if key in allowed:
            known[key] = item
        else:
            with errors.check():
                check_keys({key: item}, allowed, prefix)
    return Table(known, prefix)


class _AlreadyReported(SpecError):
    def __init__(self) -> None:
        super().__init__("", "reported already")


def _motor(value: Any) -> tuple[Motor, dict]:
    motor, raw, _ = _motor_logged(value)
    return motor, raw


def _motor_logged(value: Any, base: Path | None = None) -> tuple[Motor, dict, list]:
    """The motor, the resolved table as given (catalog applied) and the
    conversion log of the datasheet keys and unit strings. ``base``: the
    spec file's folder, against which ``flux_map`` is resolved."""
    if value is None:
        raise SpecError("motor", "a [motor] table (missing)")
    errors = Collector()
    magnetics, value = _magnetics(value, base, errors)
    t = _lenient_table(value, "motor", MOTOR_KEYS, errors)
    catalog: dict[str, Any] = {}
    if t.has("catalog"):
        name = t.string("catalog", choices=sorted(CATALOG))
        catalog = {k: v for k, v in CATALOG[name].items() if v is not None}
    # datasheet keys -> model keys; the raw table keeps what was written, so
    # reloading it (controller.json's spec) converts the same way again
    merged, log = resolve_motor(t.data, catalog, errors)
    if magnetics is not None:
        magnetics = _nominal(magnetics, merged, errors)
    raw = {**catalog_kept(catalog, t.data), **dict(t.data)}
    if "flux_map" in raw or "saturation" in raw:  # Ld, Lq, flux derived, not given
        raw = {k: v for k, v in raw.items() if k not in ("Ld", "Lq", "flux")}
    t = _Unreported(merged, "motor", reported_keys(errors, "motor"))
    fields = dict(
        R=_collect(errors, t.number, "R", positive=True, unit="ohm"),
        Ld=_collect(errors, t.number, "Ld", positive=True, unit="H"),
        Lq=_collect(errors, t.number, "Lq", positive=True, unit="H"),
        flux=_collect(errors, t.number, "flux", nonnegative=True, unit="Wb"),
        pole_pairs=_collect(errors, t.integer, "pole_pairs", minimum=1),
        J=_collect(errors, t.number, "J", positive=True, unit="kg m^2"),
        friction=_collect(errors, t.number, "friction", 0.0, nonnegative=True,
                          unit="N m s/rad"),
        convention=_collect(errors, t.string, "convention", "amplitude",
                            choices=("amplitude", "power")),
        rated_current=_collect(errors, t.number, "rated_current", None, positive=True,
                               unit="A"),
        max_current=_collect(errors, t.number, "max_current", None, positive=True, unit="A"),
        rated_speed=_collect(errors, t.number, "rated_speed", None, positive=True,
                             unit="rad/s"),
    )
    if errors.failed:
        errors.raise_if_any()
    motor = Motor(**fields, catalog=t.raw("catalog"), magnetics=magnetics)
    return motor, {k: v for k, v in raw.items() if v is not None}, log


def _magnetics(value: Any, base: Path | None, errors: Collector) -> tuple[Any, Any]:
    """A saturated motor's magnetic model (``flux_map`` or ``saturation``,
    :mod:`toolbox.spec._flux_map`) and the ``[motor]`` table with the
    flux-map path made absolute, so that controller.json's spec reloads
    from anywhere (its nominal ``Ld``, ``Lq``, ``flux``: :func:`_nominal`).
    Unchanged when neither key is given."""
    if not isinstance(value, Mapping) or not ("flux_map" in value or "saturation" in value):
        return None, value
    from ._flux_map import read_flux_map, read_saturation
    if "flux_map" in value and "saturation" in value:
        errors.add(SpecError("motor.saturation", "flux_map or saturation, not both",
                             "both given"))
        return None, value
    given = [k for k in ("Ld", "Lq", "flux", "L_ll", "ke_ll_peak", "ke_ll_rms", "kt_peak",
                         "kt_rms", "catalog") if k in value]
    if given:
        errors.add(SpecError(f"motor.{given[0]}", "no value: a saturated motor's Ld, Lq and "
                             "flux come from its flux map or saturation model", value[given[0]]))
        return None, value
    try:
        if "flux_map" in value:
            model = read_flux_map(value["flux_map"], base)
        else:
            model = read_saturation(value["saturation"])
    except SpecError as err:
        errors.add(err)
        return None, value
    table = dict(value)
    if "flux_map" in value:
        table["flux_map"] = model.data.source
    return model, table


def _nominal(model: Any, merged: dict, errors: Collector) -> Any:
    """Fill ``merged`` (the converted ``[motor]`` table) with a saturated
    motor's nominal ``Ld``, ``Lq``, ``flux``: ``MagneticModel.nominal`` at
    the MTPA point of the rated current (else the maximum current; one of them
    is required). Returns the model with that nominal current, or None after
    an error."""
    from dataclasses import replace
    current = merged.get("rated_current", merged.get("max_current"))
    if isinstance(current, bool) or not isinstance(current, (int, float)) or not current > 0:
        if current is None:
            errors.add(SpecError("motor.rated_current", "a number (A): a saturated motor's "
                                 "nominal Ld, Lq are taken at the MTPA point of its rated "
                                 "current (or max_current)", "missing"))
        return None
    model = replace(model, nominal_current=float(current))
    try:
        Ld, Lq, flux = model.nominal()
    except ValueError as err:
        errors.add(SpecError("motor.flux_map" if model.kind == "map" else "motor.saturation",
                             "an invertible magnetic model", str(err)))
        return None
    merged.update(Ld=Ld, Lq=Lq, flux=flux)
    return model


def _drive(value: Any) -> Drive:
    return _drive_logged(value)[0]


def _drive_logged(value: Any) -> tuple[Drive, list]:
    if value is None:
        raise SpecError("drive", "a [drive] table (missing)")
    errors = Collector()
    t = _lenient_table(value, "drive", DRIVE_KEYS, errors)
    merged, log = resolve_drive(t.data, errors)
    t = _Unreported(merged, "drive", reported_keys(errors, "drive"))
    fields = dict(
        vdc=_collect(errors, t.number, "vdc", positive=True, unit="V"),
        sample_time=_collect(errors, t.number, "sample_time", positive=True, unit="s"),
        delay_samples=_collect(errors, t.integer, "delay_samples", 1, minimum=0),
        switching_frequency=_collect(errors, t.number, "switching_frequency", None,
                                     positive=True, unit="Hz"),
        voltage_limit=_collect(errors, t.string, "voltage_limit", "circle",
                               choices=("circle", "hexagon")),
        max_speed=_collect(errors, t.number, "max_speed", None, positive=True, unit="rad/s"),
        hold_frame=_collect(errors, t.string, "hold_frame", "rotor",
                            choices=("rotor", "stationary")),
        angle_compensation=_collect(errors, _angle_compensation, t),
        voltage_priority=_collect(errors, t.string, "voltage_priority", "radial",
                                  choices=("radial", "d_axis")),
    )
    if errors.failed:
        errors.raise_if_any()
    drive = Drive(**fields)
    try:
        _check_drive_timing(drive)
    except SpecError as err:  # names sample_frequency when that is what the user wrote
        raise relocate(err, log) from None
    return drive, log


def _angle_compensation(t: Table) -> str | float:
    """``drive.angle_compensation``: ``"mid_period"`` (default), ``"none"`` or a
    rotation time in seconds (0 .. 20 sample periods, checked with the timing)."""
    value = t.raw("angle_compensation", "mid_period")
    if isinstance(value, str):
        return t.string("angle_compensation", "mid_period", choices=("mid_period", "none"))
    return t.number("angle_compensation", nonnegative=True, unit="s")


def _check_drive_timing(drive: Drive) -> None:
    if drive.delay_samples > 10:
        raise SpecError("drive.delay_samples", "at most 10 periods of computation delay",
                        drive.delay_samples)
    if drive.angle_compensation_time > 20 * drive.sample_time:
        raise SpecError("drive.angle_compensation", "a rotation time of at most 20 sample "
                        f"periods ({20 * drive.sample_time:g} s), \"mid_period\" or \"none\"",
                        drive.angle_compensation)
    if drive.switching_frequency is not None:
        half_periods = drive.sample_time * 2 * drive.switching_frequency
        if half_periods < 1 - 1e-9 or abs(half_periods - round(half_periods)) > 1e-6:
            raise SpecError(
                "drive.sample_time",
                "a whole number of half PWM periods (1/(2 switching_frequency) = "
                f"{0.5 / drive.switching_frequency:g} s)", drive.sample_time,
                hint="sample once or twice per carrier period: sample_time = "
                     f"{max(1, round(half_periods)) * 0.5 / drive.switching_frequency:g} s "
                     f"(sample_frequency = "
                     f"{2 * drive.switching_frequency / max(1, round(half_periods)):g} Hz)")


def _controller(value: Any, motor: Motor, drive: Drive) -> ControllerChoice:
    if value is None:
        raise SpecError("controller", "a [controller] table (missing)")
    t = Table(value, "controller")
    method = t.string("method", choices=METHODS)
    check_keys(t.data, ("method", method), "controller")
    # quantity strings ("2 kHz") -> SI before the method's reader sees them
    errors = Collector()
    table = convert_method_units(method, t.raw(method, {}), t.key(method), errors)
    # the design methods register their readers (spec/_methods.py): spec stays data;
    # a unit that does not convert is reported with every other error of the table
    cfg = read_method_cfg(method, Table(table, t.key(method)), motor=motor, drive=drive,
                          prior=errors.errors)
    return ControllerChoice(method=method, cfg=cfg)


#: Stand-in motors and drives for reading [controller] when the spec's own
#: failed: paper 003's servo at 10 kHz and a traction IPM at 20 kHz.
_STAND_INS = (({"catalog": "azaiz2007"}, {"vdc": 150, "sample_time": 1e-4}),
              ({"R": 0.01, "Ld": 1.3e-4, "Lq": 3.5e-4, "flux": 0.06, "pole_pairs": 6,
                "J": 0.04}, {"vdc": 360, "sample_time": 5e-5}))


def _controller_alone(value: Any, drive: Drive | None) -> list[SpecError]:
    """The errors of ``[controller]`` that do not depend on the motor (or on
    the drive when that failed too): the table is read against two very
    different stand-in motors (:data:`_STAND_INS`) and only the errors both
    readings give, word for word, are kept (an unknown key, a unit that
    does not parse, a negative bandwidth; never a range computed from the
    stand-in's numbers). A missing table is reported only once the motor
    and drive are valid (as before: the file is likely a fragment)."""
    if value is None:
        return []
    found = []
    for motor_table, drive_table in _STAND_INS:
        try:
            _controller(value, _motor(motor_table)[0],
                        drive if drive is not None else _drive(drive_table))
            found.append({})
        except SpecError as err:
            errs = err.errors if hasattr(err, "errors") else [err]
            found.append({str(e): e for e in errs})
    return [e for text, e in found[0].items() if text in found[1]]


def _method_name(value: Any) -> str | None:
    """``controller.method`` checked alone (None without a [controller] table)."""
    if value is None:
        return None
    return Table(value, "controller").string("method", choices=METHODS)


def _known_method(value: Any) -> str | None:
    """The method named by a raw [controller] table, or None when it is not valid."""
    try:
        return _method_name(value)
    except SpecError:
        return None


def _export_prefix(value: Any) -> str:
    """``[export] prefix``: the C prefix of controller.h (default ``cct_``)."""
    t = Table(value, "export", EXPORT_KEYS)
    prefix = t.string("prefix", "cct_")
    if not _C_PREFIX.fullmatch(prefix) or prefix == "_":
        raise SpecError("export.prefix", "a C identifier prefix: a letter, then letters, "
                        'digits or _ (at most 31 characters), e.g. "motor1_"', prefix)
    return prefix


def _requirements(value: Any) -> Requirements:
    errors = Collector()
    t = _lenient_table(value, "requirements", (*REQUIREMENT_KEYS, "parameter_drift"), errors)
    bounds = {}
    for key in t.data:  # every bound checked: all errors of the table in one run
        if key == "parameter_drift":
            continue
        unit = REQUIREMENT_KEYS[key][3]
        with errors.check():
            bounds[key] = t.number(key, unit=unit, nonnegative=key != "min_gain_margin_db",
                                   kind=REQUIREMENT_KINDS.get(key))
            check_requirement(key, bounds[key])
    ranges = {}
    if t.has("parameter_drift"):
        drift = _lenient_table(t.raw("parameter_drift"), t.key("parameter_drift"),
                               DRIFT_PARAMETERS, errors)
        if not drift.data and not errors.failed:
            errors.add(SpecError(drift.prefix, "factor ranges of at least one of "
                                 + ", ".join(DRIFT_PARAMETERS), {}))
        for name in drift.data:
            with errors.check():
                ranges[name] = _drift_range(drift, name)
    errors.raise_if_any()
    return Requirements(bounds, ranges)


def _drift_range(table: Table, name: str) -> tuple[float, float]:
    """``[low, high]`` factors around the nominal value: low <= 1 <= high."""
    lo_max, hi_max = DRIFT_FACTOR_RANGE
    low, high = table.numbers(name, length=2, unit="factors on the nominal value")
    if not (lo_max <= low <= 1.0 <= high <= hi_max):
        raise SpecError(table.key(name), f"[low, high] with {lo_max:g} <= low <= 1 <= high "
                        f"<= {hi_max:g} (factors on the nominal value)", [low, high])
    return (low, high)


#: Requirements whose ``rad/s`` or ``1/s`` is not an angular rate: a speed
#: error takes rpm (not Hz), a switching count per second takes kHz.
REQUIREMENT_KINDS = {"max_static_speed_error": "speed",
                     "max_commutations_per_s": "frequency"}


#: Longest verification scenario (s): the plant is integrated at about 1 us.
MAX_SCENARIO_DURATION = 60.0


def _convention(motor: Any) -> str:
    """The dq convention a raw [motor] table names (for rms currents)."""
    value = motor.get("convention") if isinstance(motor, Mapping) else None
    return value if value in ("amplitude", "power") else "amplitude"


def _scenarios(value: Any, drive: Drive, method: str | None, errors: Collector,
               convention: str = "amplitude") -> tuple:
    """Every ``[[scenario]]`` table, each error recorded in ``errors`` (all
    scenarios are read: every error of the file in one run); the valid
    scenarios are returned."""
    if not isinstance(value, list):
        raise SpecError("scenario", "an array of tables [[scenario]]", value)
    check_scenario_count(len(value))  # before reading 10,000 tables
    out = []
    for k, item in enumerate(value):
        key = f"scenario[{k}]"
        before = len(errors.errors)
        item = convert_scenario(item, key, convention, errors)
        if len(errors.errors) > before:
            continue
        with errors.check():
            out.append(_scenario(item, key, drive, method))
    return tuple(out)


def _scenario(item: Any, key: str, drive: Drive, method: str | None):
    """One ``[[scenario]]`` table (its unit strings already in SI)."""
    scenario = Scenario.from_dict(item, key=key, sample_time=drive.sample_time)
    if scenario.kind in ("load_step", "speed_step") and "kp" not in scenario.speed_loop:
        raise SpecError(f"{key}.speed_loop", "a table with at least kp (A s/rad) for kind "
                        f'"{scenario.kind}"', dict(scenario.speed_loop))
    ts_speed = scenario.speed_loop.get("sample_time")
    if ts_speed is not None:
        ratio = ts_speed / drive.sample_time
        if ratio < 1 - 1e-9 or abs(ratio - round(ratio)) > 1e-6:
            raise SpecError(f"{key}.speed_loop.sample_time", "a whole multiple of "
                            f"drive.sample_time ({drive.sample_time:g} s)", ts_speed)
    if scenario.inverter == "fcs_mpc" and method is not None and method != "fcs_mpc":
        raise SpecError(f"{key}.inverter", '"average" or "svm"', "fcs_mpc",
                        hint='predictive switching needs controller.method = "fcs_mpc"')
    if scenario.duration > MAX_SCENARIO_DURATION:
        raise SpecError(f"{key}.duration", f"at most {MAX_SCENARIO_DURATION:g} s",
                        scenario.duration,
                        hint="longer runs: call toolbox.sim.simulate directly")
    return scenario


def _check_scenario_plants(scenarios: tuple, motor: Motor, drive: Drive,
                           errors: Collector) -> None:
    """What a scenario asks of the motor and drive, by the rules of [motor] and
    [drive] (toolbox/spec/_bounds.py): its true plant within the motor ranges,
    its speeds below the Nyquist speed, and at least one controller period."""
    for k, sc in enumerate(scenarios):
        key = f"scenario[{k}]"
        check_plant_variant(motor, drive, dict(sc.plant_values), dict(sc.plant_scale), key,
                            errors)
        with errors.check():
            if not sc.duration >= drive.sample_time:
                raise SpecError(f"{key}.duration", "at least one controller period "
                                f"(drive.sample_time = {drive.sample_time:g} s)", sc.duration)
        with errors.check():
            check_speed(f"{key}.initial_speed", sc.initial_speed, motor, drive)
        with errors.check():
            if sc.acceleration:
                final = sc.initial_speed + sc.acceleration * sc.duration
                if not math.isfinite(final):
                    final = math.copysign(math.inf, sc.acceleration)
                try:
                    check_speed(f"{key}.acceleration", final, motor, drive)
                except SpecError as err:
                    raise SpecError(err.key, err.expected.replace(
                        "a mechanical speed", "an acceleration whose final speed "
                        "initial_speed + acceleration x duration is", 1),
                        sc.acceleration) from None


def motor_from_dict(table: Mapping[str, Any]) -> Motor:
    """Validate a ``[motor]`` table alone (catalog defaults applied).

    Parameters
    ----------
    table : mapping
        The ``[motor]`` table of a spec.

    Raises
    ------
    SpecError
        Naming the ``motor.*`` key path.
    """
    return _motor(table)[0]


def drive_from_dict(table: Mapping[str, Any]) -> Drive:
    """Validate a ``[drive]`` table alone.

    Parameters
    ----------
    table : mapping
        The ``[drive]`` table of a spec.

    Raises
    ------
    SpecError
        Naming the ``drive.*`` key path.
    """
    return _drive(table)
