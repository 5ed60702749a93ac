"""The Optimize panel mounted in the explorer: its settings travel in the link (and only those that
differ from the defaults), a run's front design loads into the session's design sliders."""

from __future__ import annotations

import pytest
from explorer_client import FakeBrowser, wait_for, wait_idle  # tests/ (pytest's prepend import mode)

from paraspace.app.explorer import Explorer
from paraspace.app.explorer.optimize_panel import URL_KEYS
from paraspace.app.explorer.pagehook import page_refusal
from paraspace.app.urlstate import OPT_KEYS, parse_query


@pytest.fixture(scope="module")
def explorer():
    exp = Explorer("127.0.0.1", 0).start()
    exp.warm.wait(120)
    yield exp
    exp.stop()


def test_link_keys_match_the_panel():
    assert set(OPT_KEYS) == set(URL_KEYS)
    assert page_refusal("/", "a=60&opt_pop=8") is None
    assert parse_query("a=60&opt_pop=8")[1] == []


@pytest.mark.slow
def test_optimize_tab_round_trip_and_load(explorer):
    b = FakeBrowser(explorer, "voxel=6&opt_pop=4&opt_gen=1&opt_voxel=12&opt_params=a,l_s")
    try:
        s = b.session
        opt = s.optimize
        assert opt is not None and int(opt.population.value) == 4 and float(opt.voxel.value) == 12.0
        wait_for(lambda: "opt_pop=4" in b.search, 5.0, "the panel's settings in the address bar")
        assert "opt_objectives" not in b.search  # defaults are left out of the link
        wait_idle(explorer, s)
        job = opt.run()
        assert job is not None and job.wait(120) and job.status == "done"
        wait_for(lambda: opt.result is not None and opt.result["front"], 10.0, "the front")
        design = opt.load_selected()
        assert design is not None
        wait_for(lambda: s.state.design == design, 10.0, "the loaded design")
        assert s.panels.design["a"].value == design.a
    finally:
        b.close()
