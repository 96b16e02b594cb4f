"""Helpers of the campaign tests: a small campaign on paper 003's motor (catalog azaiz2007).

PI by pole-zero cancellation at 600 rad/s, one 20 ms i_q step, R, Ld, Lq and
flux drawn (Ld, Lq correlated), a grid of 8 operating points (speed,
speed-sensor offset, computation delay). The bounds are set so
that a few per cent of the samples fail (rise time with large R and small L,
overshoot), so that pass/fail and the failure columns are exercised.
"""

from __future__ import annotations

from pathlib import Path

SPEC = '''title = "campaign test <on> paper 003's motor"
[motor]
catalog = "azaiz2007"
[drive]
vdc = 150
sample_time = 1e-4
delay_samples = 1
[controller]
method = "pi"
[controller.pi]
rule = "cancellation"
bandwidth = 600.0
[requirements]
min_phase_margin_deg = 55
max_overshoot_pct = 5.0
max_rise_time = 0.006
[[scenario]]
name = "iq step"
kind = "current_step"
duration = 0.02
iq_ref = 10.0
[campaign]
samples = {samples}
seed = 3
chunk_size = {chunk_size}
[campaign.parameters.R]
distribution = "uniform"
low = 1.0
high = 1.4
[campaign.parameters.Ld]
distribution = "truncnormal"
mean = 0.85
std = 0.1
low = 0.7
high = 1.0
[campaign.parameters.Lq]
distribution = "uniform"
low = 0.5
high = 1.0
[campaign.parameters.flux]
distribution = "normal"
mean = 0.95
std = 0.02
[campaign.correlation]
parameters = ["Ld", "Lq"]
matrix = [[1.0, 0.8], [0.8, 1.0]]
[campaign.operating_points]
speed = [0.0, 100.0]
speed_offset = [0.0, 5.0]
delay_samples = [1, 2]
'''


def write_spec(directory: Path, samples: int = 400, chunk_size: int = 100,
               extra: str = "") -> Path:
    """The test campaign spec written to ``directory/campaign.toml``."""
    path = Path(directory) / "campaign.toml"
    path.write_text(SPEC.format(samples=samples, chunk_size=chunk_size) + extra)
    return path


def flaky_evaluate(log_dir: str, faults: dict, plan, start: int, stop: int):
    """``toolbox.campaign.evaluate_chunk`` with injected faults: the chunk
    starting at row ``start`` raises ``RuntimeError`` at its first
    ``faults[start]`` attempts. Every attempt appends a line to
    ``log_dir/<start>`` (counted across worker processes)."""
    import os

    from toolbox.campaign import evaluate_chunk

    path = os.path.join(log_dir, str(start))
    with open(path, "a") as fh:
        fh.write("attempt\n")
    with open(path) as fh:
        attempt = len(fh.read().splitlines())
    if attempt <= faults.get(start, 0):
        raise RuntimeError(f"injected fault at rows {start}..{stop - 1}")
    return evaluate_chunk(plan, start, stop)
