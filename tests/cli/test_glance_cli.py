"""The CLI's verdict at a glance: fcs_mpc's margins are the baseline PI's."""

from __future__ import annotations

import types

from toolbox.cli._main import _summary


def _out(method):
    m = {"gain_margin_db": -3.871, "phase_margin_deg": -63.96, "stability_margin": 0.1}
    art = types.SimpleNamespace(method=method, margins={"d": m, "q": m})
    return types.SimpleNamespace(warnings=[], verification=None, notice=None, artifact=art,
                                 analysis=None, header_refused=None)


def test_fcs_mpc_margins_printed_as_baseline(capsys):
    _summary(_out("fcs_mpc"))
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == ("d axis (baseline PI, informational, not executed): GM -3.871 dB, "
                        "PM -63.96 deg, Mm 0.1")
    _summary(_out("pi"))
    assert capsys.readouterr().out.startswith("d axis (sampled loop): GM -3.871 dB")
