"""The report's twin rig (tactile.thesis_experiments.twin_rig): compiled stepping, the numpy twin's readings."""

import numpy as np
import pytest

from flexdigit.rig.base import open_rig
from flexdigit.tactile.protocols import load_protocol
from flexdigit.tactile.runner import collect, sim_options
from flexdigit.tactile.thesis_experiments import twin_rig


@pytest.mark.parametrize(("name", "seed"), [("thesis-6.1", 3), ("thesis-7.1", 4)])
def test_the_compiled_twin_reads_what_the_numpy_twin_reads(tmp_path, name, seed):
    # The kernel follows the numpy twin to ~1e-15 rad; the 16-bit ADC's quantum (~0.15 mV) hides that, so the
    # readings (and everything the report computes from them) are the numpy twin's, bit for bit
    protocol = load_protocol(name)
    fast = twin_rig(protocol, seed=seed)
    assert fast.compiled
    slow = open_rig("sim", seed=seed, **sim_options(protocol))
    assert not slow.compiled
    try:
        a = collect(protocol, fast, tmp_path / "compiled.parquet", rig_url="sim", settle_s=0.5)
        b = collect(protocol, slow, tmp_path / "numpy.parquet", rig_url="sim", settle_s=0.5)
    finally:
        fast.close()
        slow.close()
    assert a.columns.keys() == b.columns.keys()
    for column in a.columns:  # the gauges, the servo, the settings, the times
        assert np.array_equal(a[column], b[column], equal_nan=a[column].dtype.kind == "f"), column
    assert a.meta["settings"]["rig"]["compiled"]
    assert "compiled" not in b.meta["settings"]["rig"]
