"""The run checks (setup.run_checks): a run whose outputs and model would not fit the
machine's memory is refused before it starts, naming t_end, what the outputs and the model
need and what to change; one that fits runs."""

from __future__ import annotations

import pytest

from granplate.bench.scaling_space import launched_fcc
from granplate.errors import ScenarioError
from granplate.setup import run_checks
from granplate.setup.run_checks import MODEL_BYTES_PER_GRANULE, output_bytes_per_second
from granplate.setup.validate import validate

GB = 1e9


def fcc(outputs: int):
    """The launched FCC packing of 10,192 spheres in space, `outputs` output intervals."""
    return launched_fcc((14, 14, 13), mu=0.0, scheme="verlet", t_end=2e-6, outputs=outputs)


def test_outputs_beside_the_model_must_fit_the_memory(monkeypatch):
    """With the machine's memory set between the outputs alone and the outputs with the
    model (which the run needs too: an out-of-memory kill, no message, when it was left
    out), the run is refused naming both shares; with more it is accepted."""
    s = fcc(20)
    outputs = output_bytes_per_second(s) * s.time.t_end
    model = MODEL_BYTES_PER_GRANULE * len(s.granules)
    share = run_checks.MEMORY_SHARE
    monkeypatch.setattr(run_checks, "physical_memory", lambda: (outputs + 0.5 * model) / share)
    with pytest.raises(ScenarioError) as e:
        validate(s)
    text = str(e.value)
    assert "time.t_end" in text and "for the model of 10192 granules" in text and "raise" in text
    monkeypatch.setattr(run_checks, "physical_memory", lambda: 1.05 * (outputs + model) / share)
    validate(s)


def test_a_packing_in_space_counts_its_contact_rows():
    """A close packing in space lists about 6 contacts a granule in its contact table, the
    plane's about 3: the table's share of the outputs is counted so."""
    s = fcc(20)
    per_output = output_bytes_per_second(s) * s.time.output_interval / len(s.granules)
    assert per_output > run_checks.OUTPUT_BYTES_PER_GRANULE + 6 * run_checks.LINK_BYTES_PER_ROW - 1.0
