"""A saturated motor's controller records the magnetic data it was designed
on (toolbox/ARCHITECTURE.md "controller.json", ``provenance.magnetics_sha256``):
for a flux map the SHA-256 of the file's bytes (what ``sha256sum file.csv``
prints), for ``[motor.saturation]`` the SHA-256 of its parameters' canonical
JSON; a constant-parameter motor's artifact has no such key; the value
round-trips through controller.json and is printed in controller.h.

The spec's own hash does not cover a map: the spec holds only its path, so an
edited map under the same name would otherwise leave no trace."""

from __future__ import annotations

import hashlib
import json
import tomllib
from dataclasses import asdict
from pathlib import Path

import toolbox
from toolbox.artifact import ControllerArtifact
from toolbox.export import write_header

ROOT = Path(__file__).resolve().parents[2]
PMSYRM = ROOT / "tests" / "corpus" / "motors" / "baldor_ecs101m0h7ef4_pmsyrm.toml"
LD, LQ, FLUX = 2e-3, 5e-3, 0.1


def _map_spec(tmp_path, psi_scale=1.0):
    rows = [f"{a},{b},{(LD * a + FLUX) * psi_scale!r},{LQ * b * psi_scale!r}"
            for a in (-20.0, 0.0, 20.0) for b in (-20.0, 0.0, 20.0)]
    (tmp_path / "m.csv").write_text("i_d,i_q,psi_d,psi_q\n" + "\n".join(rows) + "\n")
    (tmp_path / "s.toml").write_text(
        'title = "m"\n[motor]\nR = 0.1\npole_pairs = 4\nJ = 0.01\nmax_current = 20\n'
        'flux_map = "m.csv"\n[drive]\nvdc = 300\nsample_time = 1e-4\n'
        '[controller]\nmethod = "pi"\n')
    return toolbox.load_spec(tmp_path / "s.toml")


def test_flux_map_file_hash(tmp_path):
    spec = _map_spec(tmp_path)
    art = toolbox.design_spec(spec)
    file_hash = hashlib.sha256((tmp_path / "m.csv").read_bytes()).hexdigest()
    assert art.provenance["magnetics_sha256"] == file_hash
    again = ControllerArtifact.from_json(json.loads(json.dumps(art.to_json())))
    assert again.provenance["magnetics_sha256"] == file_hash
    header = write_header(art, spec.motor, spec.drive)
    assert f" * magnetics sha256: {file_hash}\n" in header
    # another map under the same name: same spec hash, another magnetics hash
    other = toolbox.design_spec(_map_spec(tmp_path, psi_scale=1.01))
    assert other.provenance["spec_sha256"] == art.provenance["spec_sha256"]
    assert other.provenance["magnetics_sha256"] != file_hash


def test_corpus_flux_map_hash():
    """The SyR-e THOR map of the corpus (tests/corpus/motors/flux_maps)."""
    path = ROOT / "tests" / "corpus" / "motors" / "syre_thor_5kw_pmsyrm.toml"
    spec = toolbox.spec_from_dict(tomllib.loads(path.read_text()), file=str(path))
    art = toolbox.design_spec(spec)
    csv = path.parent / "flux_maps" / "syre_thor_5kw.csv"
    assert art.provenance["magnetics_sha256"] == hashlib.sha256(csv.read_bytes()).hexdigest()


def test_algebraic_parameters_hash():
    data = tomllib.loads(PMSYRM.read_text())
    spec = toolbox.spec_from_dict(data)
    art = toolbox.design_spec(spec)
    params = asdict(spec.motor.magnetics.data)
    want = hashlib.sha256(json.dumps({k: float(v) for k, v in params.items()},
                                     sort_keys=True).encode()).hexdigest()
    assert art.provenance["magnetics_sha256"] == want
    data["motor"]["saturation"]["a_qq"] *= 1.001
    changed = toolbox.design_spec(toolbox.spec_from_dict(data))
    assert changed.provenance["magnetics_sha256"] != want


def test_constant_motor_has_no_magnetics_hash():
    spec = toolbox.load_spec(ROOT / "designs" / "003_azaiz2007_pi.toml")
    art = toolbox.design_spec(spec)
    assert "magnetics_sha256" not in art.provenance
    assert "magnetics sha256" not in write_header(art, spec.motor, spec.drive)
