"""Property-based checks (hypothesis, issue 14): parameters of every study and of the scene API,
drawn from inside and just outside their allowed ranges, end either with a dataset that passes its
contract or with the one-line error — never a traceback, never a partial file.

Cheap by design: the solvers are not run (each study's sweep is replaced by one that returns a
failed-run status, which a study must store as a result like any other); what is exercised is the
checking before work (:func:`studies.common.validate`, :class:`workbench.scenes.Scene`), the
scene models, the study's own reference computations (closed forms, elastica) and the dataset it
writes."""
import dataclasses
import math
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import studies
from studies import common
from studies.microcantilever import MicroCantilever
from studies.rc_beam import RCBeam
from workbench import results
from workbench.scenes import (SCENES, STABILITY_SCENES, VERIFICATION_SCENES,
                              ParameterError, with_overrides)

ALL_SCENES = {**SCENES, **STABILITY_SCENES, **VERIFICATION_SCENES, "rc_beam": RCBeam,
              "microcantilever": MicroCantilever}
SETTINGS = settings(max_examples=25, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


def _fields(cls):
    return [f for f in dataclasses.fields(cls) if not f.metadata.get("hidden")]


@st.composite
def inside(draw, md, d):
    """A value the parameter's own range allows (a cross-parameter check may still refuse it)."""
    if md.get("choices"):
        return draw(st.sampled_from(md["choices"]))
    if isinstance(d, bool):
        return draw(st.booleans())
    lo, hi = md.get("lo"), md.get("hi")
    if isinstance(d, int):
        a = lo if lo is not None else d - 10
        b = hi if hi is not None else max(d, a) * 4 + 10
        a += 1 if md.get("lo_open") else 0
        b -= 1 if md.get("hi_open") else 0
        return draw(st.integers(int(a), int(max(a, min(b, d * 4 + 10)))))
    if isinstance(d, tuple):
        return tuple(draw(st.lists(inside(md, float(d[0])), min_size=1, max_size=4)))
    if lo is not None and hi is not None:
        return draw(st.floats(lo, hi, exclude_min=md.get("lo_open", False),
                              exclude_max=md.get("hi_open", False)))
    ref = d if (math.isfinite(d) and d != 0) else 1.0
    v = ref * 10.0 ** draw(st.floats(-3, 3))
    if lo is not None and not (v > lo or (v == lo and not md.get("lo_open"))):
        v = abs(v) + lo + abs(ref)
    return v


@st.composite
def outside(draw, md, d):
    """A value just outside the parameter's allowed range (or not a value of its type)."""
    if md.get("choices"):
        return draw(st.sampled_from(["bogus", "", "STRAIN"]))
    if isinstance(d, bool):
        return draw(st.sampled_from(["maybe", "2"]))
    lo, hi = md.get("lo"), md.get("hi")
    bad = [math.nan, -math.inf] + ([] if md.get("allow_inf") else [math.inf])
    if lo is not None:
        bad.append(lo if md.get("lo_open") else
                   (lo - 1 if isinstance(d, int) else lo - max(abs(lo), 1.0) * 1e-9))
    if hi is not None:
        bad.append(hi if md.get("hi_open") else
                   (hi + 1 if isinstance(d, int) else hi + max(abs(hi), 1.0) * 1e-9))
    if isinstance(d, int):
        bad = [b for b in bad if isinstance(b, int)] + [2.5]
    if isinstance(d, tuple):
        one = draw(st.sampled_from(bad))
        return draw(st.sampled_from([(), (float(d[0]), one)]))
    return draw(st.sampled_from(bad))


def _text(v) -> str:
    if isinstance(v, tuple):
        return ",".join(repr(float(x)) for x in v)
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


@st.composite
def scene_and_case(draw, cls):
    """(scene or ParameterError, any_outside): 1-3 parameters changed, each inside or just
    outside its range, through the command line's ``--set`` text or the Python API."""
    fs = draw(st.lists(st.sampled_from(_fields(cls)), min_size=1, max_size=3, unique_by=lambda f: f.name))
    changes, bad = {}, False
    for f in fs:
        if draw(st.booleans()):
            changes[f.name] = draw(outside(f.metadata, f.default))
            bad = True
        else:
            changes[f.name] = draw(inside(f.metadata, f.default))
    via_text = draw(st.booleans())
    try:
        if via_text:
            scene = with_overrides(cls(), {k: _text(v) for k, v in changes.items()})
        else:
            scene = dataclasses.replace(cls(), **changes)
    except ParameterError as err:
        return err, bad, changes
    return scene, bad, changes


def _one_line(err, changes=None):
    """One line, 'WHAT: why …' — WHAT the parameter(s) or the part of the model at fault."""
    msg = str(err)
    assert msg and "\n" not in msg and "Traceback" not in msg, msg
    name, sep, why = msg.partition(": ")
    assert sep and why and 0 < len(name) <= 60, msg


@pytest.mark.parametrize("name", sorted(ALL_SCENES))
@SETTINGS
@given(data=st.data())
def test_scene_api_refuses_or_builds(name, data):
    cls = ALL_SCENES[name]
    scene, bad, changes = data.draw(scene_and_case(cls))
    if isinstance(scene, ParameterError):
        _one_line(scene, changes)
        return
    assert not bad, f"{changes} accepted"  # a value outside its range is never accepted
    try:
        model = scene.model()
    except ParameterError as err:  # SceneError: the parameters do not hold together
        _one_line(err)
        return
    assert model.length > 0 and math.isfinite(model.length)


def _fake_run_tasks(tasks, scheduler=None, title=""):
    return [{"status": "error: not run (property test)"} for _ in tasks]


REQUIRED = {"ss_curve": ("stress", "nominal_stress", "wall_time", "status"),
            "cantilever": ("tip_deflection", "tip_horizontal", "wall_time", "status"),
            "plate": ("period", "amplitude", "tip_displacement", "wall_time", "status")}


@pytest.mark.parametrize("name", sorted(studies.STUDIES))
@SETTINGS
@given(data=st.data())
def test_study_ends_with_a_dataset_or_one_line(name, data, tmp_path_factory):
    study = studies.get(name)
    scene, bad, changes = data.draw(scene_and_case(study.SCENE))
    resolutions = data.draw(st.one_of(st.none(), st.lists(st.one_of(
        st.integers(-1, 3), st.integers(10 ** 5, 10 ** 8), st.sampled_from([2.5, math.nan])),
        min_size=0, max_size=2)))
    if isinstance(scene, ParameterError):
        event("scene refused")
        _one_line(scene)
        return
    assert not bad, f"{changes} accepted"
    try:
        common.validate(study, scene, None, resolutions, quick=True)
    except ParameterError as err:
        event("run refused")
        _one_line(err)
        return
    if name not in REQUIRED:
        return  # validate-only: its sweep's scenes are fixed (stability) or its runs 3-D (micro)
    out = tmp_path_factory.mktemp(name)
    with mock.patch.object(study, "run_tasks", _fake_run_tasks):
        try:
            ds = study.run(scene=scene, resolutions=resolutions, quick=True)
        except ParameterError as err:
            _one_line(err)
            assert not any(out.iterdir())
            return
    event("dataset written")
    path = results.write(ds, out / f"{name}.nc")
    assert [p.name for p in out.iterdir()] == [f"{name}.nc"]  # no partial or temporary file
    back = results.read(path)
    for var in REQUIRED[name]:
        assert var in back, var
    for v, x in back.data_vars.items():
        assert "units" in x.attrs, v
    for key in ("study", "workbench_version", "git_revision", "date", "cpu_count"):
        assert key in back.attrs
    for f in _fields(study.SCENE):
        assert f"param_{f.name}" in back.attrs
    status = np.atleast_1d(back.status.values).ravel()
    assert all(str(s) == "not run" or str(s).startswith(("ok", "error")) for s in status)
