"""Model files: every example mechanism exists as a file in examples/models/ that builds the
same model as the example's Python (same initial state, same results of its analysis, to the
last bit); any model saved and loaded again is the same model; and mistakes in a file are
reported with the file, the line and the field.

Regenerate the example files after changing an example: python tests/test_model_files.py
"""

from __future__ import annotations

import importlib.util
import math
import pathlib
import sys
import warnings

import numpy as np
import pytest

import mbd3d as mb
from mbd3d import mechanisms
from mbd3d.io.model_file import AnalysisSpec, ModelFileError, read

ROOT = pathlib.Path(__file__).resolve().parent.parent
MODELS = ROOT / "examples" / "models"


def example(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def steps(start, stop, step):
    return {"start": start, "stop": stop, "step": step}


#: example -> (its model, the analysis its file asks for: what the example runs)
EXAMPLES = {
    "slider_crank": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 1.0, 0.005)}),
    "four_bar": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 1.0, 1 / 240)}),
    "four_bar_modes": (lambda m: m.build(), {"kind": "equilibrium",
                                             "t": steps(0.0, 1.0, 1 / 36)}),
    "pendulum_spring_equilibrium": (lambda m: m.pendulum(10.0, motor=True),
                                    {"kind": "equilibrium", "t": steps(0.0, 1.0, 1 / 6)}),
    "cart_pendulum_linearized": (lambda m: m.cart_pendulum(),
                                 {"kind": "forward", "t": steps(0.0, 1.0, 0.01),
                                  "method": "DOP853", "rtol": 1e-10}),
    "spatial_slider_crank": (lambda m: m.build(), {"kind": "inverse",
                                                   "t": steps(0.0, 1.0, 0.005)}),
    "spatial_four_bar": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 1.0, 0.005)}),
    "spinning_top": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 1.0, 0.005),
                                           "method": "DOP853", "rtol": 1e-11, "atol": 1e-12}),
    "mesh_bodies": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 2.0, 0.01),
                                          "method": "DOP853", "rtol": 1e-10, "atol": 1e-12}),
    "andrews_squeezer": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 0.03, 1e-4),
                                               "method": "DOP853", "rtol": 1e-11,
                                               "atol": 1e-14, "constraint_tol": 1e-12}),
    "haug_slider_crank": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 10.0, 0.4),
                                                "method": "DOP853", "rtol": 1e-11,
                                                "atol": 1e-13}),
    "iftomm_pendulum": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 10.0, 0.01),
                                              "method": "DOP853", "rtol": 1e-12,
                                              "atol": 1e-12}),
    "iftomm_four_bar": (lambda m: m.build(40), {"kind": "forward", "t": steps(0.0, 20.0, 0.05),
                                                "method": "generalized-alpha", "step": 1e-3}),
    "flyball_governor": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 5.0, 0.01),
                                               "method": "generalized-alpha", "step": 1e-3}),
    "bricard": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 10.0, 0.01),
                                      "method": "generalized-alpha", "step": 1e-3}),
    "gear_train": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 0.5, 0.05)}),
    "differential": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 0.5, 0.0625)}),
    "bouncing_ball": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 2.5, 0.0025),
                                            "method": "DOP853", "rtol": 1e-10, "atol": 1e-12}),
    "rolling_disc": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 4.0, 0.1),
                                           "method": "DOP853", "rtol": 1e-11, "atol": 1e-12}),
    "slider_crank_friction": (lambda m: m.build(), {"kind": "inverse",
                                                    "t": steps(0.0, 0.2, 0.2 / 72)}),
    "cam_follower": (lambda m: m.build(), {"kind": "inverse", "t": steps(0.0, 1.0, 1 / 70)}),
    "slider_crank_clearance": (lambda m: m.build(), {"kind": "forward",
                                                     "t": steps(0.0, 0.024, 6e-5),
                                                     "method": "DOP853", "rtol": 1e-8,
                                                     "atol": 1e-10}),
    "cam_jump": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 0.27, 0.001),
                                       "method": "DOP853", "rtol": 1e-9, "atol": 1e-11}),
    "newtons_cradle": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 0.35, 5e-4),
                                             "method": "DOP853", "rtol": 1e-10,
                                             "atol": 1e-12}),
    "backspin": (lambda m: m.build(-4 * m.V0 / m.RADIUS), {
        "kind": "forward", "t": steps(0.0, 2.0, 0.01), "method": "DOP853", "rtol": 1e-10,
        "atol": 1e-12}),
    "stick_slip": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 3.0, 0.01),
                                         "method": "DOP853", "rtol": 1e-10, "atol": 1e-12}),
    "rigid_impacts": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 2.0, 0.005),
                                            "method": "DOP853", "rtol": 1e-10,
                                            "atol": 1e-12}),
    "sweep_slider_crank": (lambda m: m.build(20.0, 0.3), {"kind": "inverse",
                                                           "t": steps(0.0, 1.0, 0.01)}),
    "identify_slider_crank": (lambda m: m.build(), {"kind": "inverse",
                                                    "t": steps(0.0, 0.5, 0.0025)}),
    "four_bar_synthesis": (lambda m: m.build(), {"kind": "kinematic",
                                                 "t": steps(0.0, 0.7, 0.1)}),
    "spheres_in_box": (lambda m: m.build(), {"kind": "forward", "t": steps(0.0, 0.3, 0.005),
                                             "method": "RK45", "rtol": 1e-5, "atol": 1e-8}),
}


def write_model_files() -> None:
    """The example files, from the examples' own Python."""
    MODELS.mkdir(exist_ok=True)
    for name, (make, analysis) in EXAMPLES.items():
        model = make(example(name))
        path = mb.save(model, MODELS / f"{name}.yaml", analyses=[analysis], overwrite=True)
        print("wrote", path)


def short(spec: AnalysisSpec) -> AnalysisSpec:
    """The file's analysis over its first few output times (a test's budget)."""
    count = 3 if spec.options.get("method") == "generalized-alpha" else 4
    return AnalysisSpec(spec.kind, spec.t[:count], spec.options)


def test_every_example_has_a_model_file():
    examples = {p.stem for p in (ROOT / "examples").glob("*.py")}
    assert examples == set(EXAMPLES), examples ^ set(EXAMPLES)


#: examples whose file's short run takes minutes with the compiled core interpreted
HEAVY = {"spheres_in_box"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.compiled_only)
                                  if n in HEAVY else n for n in sorted(EXAMPLES)])
def test_example_model_file_is_the_example_model(name):
    make, analysis = EXAMPLES[name]
    python_model = make(example(name))
    with warnings.catch_warnings():  # cam_jump's roller starts pressed into its cam
        warnings.simplefilter("ignore" if name == "cam_jump" else "default", mb.ContactWarning)
        loaded = read(MODELS / f"{name}.yaml")
    model = loaded.model
    assert [b.name for b in model.bodies] == [b.name for b in python_model.bodies]
    assert [e.name for e in model.joints] == [e.name for e in python_model.joints]
    assert model.row_labels == python_model.row_labels
    meshes = name == "mesh_bodies"  # masses from meshes read back from OBJ text
    tight = {"rtol": 1e-13, "atol": 1e-15} if meshes else {"rtol": 0.0, "atol": 0.0}
    np.testing.assert_allclose(model.q0, python_model.q0, **tight)
    np.testing.assert_allclose(model.qd0, python_model.qd0, **tight)
    np.testing.assert_allclose(model.mass, python_model.mass, **tight)
    assert len(loaded.analyses) == 1 and loaded.analyses[0].kind == analysis["kind"]
    spec = short(loaded.analyses[0])
    ours, theirs = spec.run(model, progress=False), spec.run(python_model, progress=False)
    if meshes:
        np.testing.assert_allclose(ours.q, theirs.q, rtol=1e-10, atol=1e-12)
    else:
        np.testing.assert_array_equal(ours.q, theirs.q)
        np.testing.assert_array_equal(ours.qd, theirs.qd)
        if ours.lam is not None:
            np.testing.assert_array_equal(ours.lam, theirs.lam)


def test_a_saved_model_loads_as_the_same_model(tmp_path):
    """Motions summed, spatial bodies with orientations and rates, meshes written beside."""
    model = mechanisms.spatial_four_bar(crank_speed=2 * math.pi)
    path = mb.save(model, tmp_path / "rsur.yaml")
    again = mb.load(path)
    np.testing.assert_array_equal(again.q0, model.q0)
    np.testing.assert_array_equal(again.charts0, model.charts0)
    from mbd3d.joints import Revolute, RotationDriver
    b = mb.ModelBuilder(dim=2, gravity=(0.0, -9.81), name="summed motion")
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    pin = b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(RotationDriver("motor", pin, motion=mb.Ramp(0.0, 2.0) + mb.Harmonic(0.1, 3.0)
                         + mb.SmoothStep(0.0, 1.0, 0.0, 0.5)))
    summed = b.build()
    again = mb.load(mb.save(summed, tmp_path / "summed.yaml"))
    t = np.linspace(0.0, 1.0, 11)
    np.testing.assert_array_equal(mb.inverse_dynamics(again, t).lam,
                                  mb.inverse_dynamics(summed, t).lam)
    text = (tmp_path / "summed.yaml").read_text()
    assert "type: Sum" in text and "Harmonic" in text


def test_functions_cannot_be_saved(tmp_path):
    from mbd3d.joints import Revolute
    b = mb.ModelBuilder(dim=2)
    bar = b.add_body("bar", mass=1.0, inertia=0.1, position=(0.5, 0.0))
    b.add(Revolute("O", b.ground, bar, at=(0.0, 0.0)))
    b.add(mb.Torque("push", bar, lambda t: math.sin(t)))
    with pytest.raises(ModelFileError, match="Torque 'push': torque: a Python function"):
        mb.save(b.build(), tmp_path / "f.yaml")
    assert not (tmp_path / "f.yaml").exists()


GOOD = """\
mbd3d: 1
name: pendulum
dim: 2
gravity: [0.0, -9.81]
bodies:
  - {name: bar, mass: 1.0, inertia: 0.1, position: [0.5, 0.0]}
joints:
  - {type: Revolute, name: O, body_i: ground, body_j: bar, at: [0.0, 0.0]}
  - type: RotationDriver
    name: motor
    joint: O
    motion: {type: Ramp, initial: 0.0, rate: 6.0}
analyses:
  - {kind: inverse, t: {start: 0.0, stop: 1.0, points: 11}}
"""


def test_values_are_read_as_yaml_1_2(tmp_path):
    # YAML 1.1 (PyYAML's reading) makes 1e-10 a string, 010 eight, 1:30 ninety and no False
    path = tmp_path / "m.yaml"
    path.write_text(GOOD.replace("mass: 1.0", "mass: 010").replace("name: bar", "name: no")
                    .replace("body_j: bar", "body_j: no").replace("name: motor", "name: 1:30")
                    .replace("points: 11}}", "points: 11}, tol: 1e-10}"))
    read_back = read(path)
    assert read_back.model.body("no").mass == 10.0
    assert "1:30" in [joint.name for joint in read_back.model.joints]
    assert read_back.analyses[0].options["tol"] == 1e-10


@pytest.mark.parametrize("text, message", [
    (GOOD.replace("name: motor\n", "name: motor\n    name: motors\n"),
     r"m.yaml:11: the key 'name' appears twice in this mapping \(lines 10 and 11\)"),
    (GOOD.replace("position: [0.5, 0.0]", "position: &p [0.5, 0.0]")
     .replace("at: [0.0, 0.0]", "at: *p"), r"m.yaml:8: anchors and aliases .* are not read"),
    (GOOD.replace("mass: 1.0", "mass: !!python/object/apply:os.system [echo]"),
     r"m.yaml:6: the tag 'tag:yaml.org,2002:python/object/apply:os.system' is not read"),
    ("a: " + "[" * 200 + "]" * 200, r"m.yaml(:1)?: (not valid YAML: exceeded maximum nesting|"
                                      r"nested more than 64 levels)"),
])
def test_duplicate_keys_aliases_and_foreign_tags_are_refused_by_line(tmp_path, text, message):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(ModelFileError, match=message):
        read(path)


def test_an_alias_bomb_is_refused_at_once(tmp_path):
    # nine levels of nine aliases: 9^9 strings once expanded (the 822-byte file of the report
    # exhausted memory through the line map), refused at the first alias without expanding
    lines = ['bodies: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for k in range(1, 9):
        lines.append(f"b{k}: &{chr(97 + k)} [" + ", ".join([f"*{chr(96 + k)}"] * 9) + "]")
    path = tmp_path / "bomb.yaml"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ModelFileError, match=r"bomb.yaml:2: anchors and aliases"):
        read(path)


@pytest.mark.parametrize("change, message", [
    (("bodies:", "bodys:"), r"m.yaml:5: bodys: unknown field \(did you mean 'bodies'\?"),
    (("body_j: bar", "body_j: bra"), r"m.yaml:8: joints\[0\].body_j: no body or joint 'bra'.*"
                                     r"did you mean 'bar'"),
    (("type: Revolute", "type: Revolut"), r"m.yaml:8: joints\[0\].type: unknown joint or "
                                          r"driver type 'Revolut' \(did you mean 'Revolute'"),
    (("at: [0.0, 0.0]}", "at: [0.0, 0.0, 1.0]}"),
     r"m.yaml:8: joints\[0\].at: joint .O.: at must"),
    (("type: Ramp", "type: Rmp"), r"m.yaml:12: joints\[1\].motion.type: unknown motion type "
                                  r"'Rmp' \(did you mean 'Ramp'"),
    (("rate: 6.0", "rat: 6.0"), r"m.yaml:12: joints\[1\].motion.rat: Ramp takes no 'rat' "
                                r"\(did you mean 'rate'"),
    (("mass: 1.0, ", ""), r"m.yaml:6: bodies\[0\]: body 'bar': give its mass"),
    (("kind: inverse", "kind: invers"), r"m.yaml:14: analyses\[0\].kind: unknown analysis"),
    (("name: motor\n", "name: motor\n    method: RK45\n"), r"m.yaml:11: joints\[1\].method: "
                                                          r"RotationDriver takes no 'method'"),
    (("[0.5, 0.0]}", "[0.5, 0.0}"), r"m.yaml:6: not valid YAML"),
])
def test_mistakes_are_reported_with_file_line_and_field(tmp_path, change, message):
    path = tmp_path / "m.yaml"
    path.write_text(GOOD.replace(*change))
    with pytest.raises(ModelFileError, match=message):
        mb.load(path)


def test_a_wrong_value_is_reported_at_its_own_line_not_its_entry_s(tmp_path):
    # the body's fields one per line: the position's line, not the body's first
    path = tmp_path / "m.yaml"
    path.write_text(GOOD.replace("  - {name: bar, mass: 1.0, inertia: 0.1, position: [0.5, 0.0]}",
                                 "  - name: bar\n    mass: 1.0\n    inertia: 0.1\n"
                                 "    position: [0.5, 0.0, 1.0]"))
    with pytest.raises(ModelFileError, match=r"m.yaml:9: bodies\[0\].position: body 'bar': "
                                             r"position must have 2 components"):
        read(path)
    path.write_text(GOOD.replace("    motion: {type: Ramp, initial: 0.0, rate: 6.0}",
                                 "    motion:\n      type: Ramp\n      initial: 0.0\n"
                                 "      rate: .nan"))
    with pytest.raises(ModelFileError, match=r"m.yaml:15: joints\[1\].motion.rate: "):
        read(path)


@pytest.mark.parametrize("spec, expected", [
    ("{start: 0.5, stop: 1.5, points: 5}", [0.5, 0.75, 1.0, 1.25, 1.5]),
    ("{stop: 1.0, points: 3}", [0.0, 0.5, 1.0]),
    ("{start: 0.0, stop: 0.3, step: 0.1}", [0.0, 0.1, 0.2, 0.3]),
    ("{start: 0.0, stop: 0.25, step: 0.1}", [0.0, 0.1, 0.2, 0.25]),  # the stop is kept
    ("[0.0, 0.2, 0.7]", [0.0, 0.2, 0.7]),
])
def test_times_in_a_file_are_the_ones_it_states(tmp_path, spec, expected):
    path = tmp_path / "m.yaml"
    path.write_text(GOOD.replace("t: {start: 0.0, stop: 1.0, points: 11}", f"t: {spec}"))
    t = read(path).analyses[0].t
    assert len(t) == len(expected)
    np.testing.assert_allclose(t, expected, rtol=0, atol=1e-15)


def test_a_good_file_runs_its_analysis_and_takes_changes(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(GOOD)
    loaded = read(path)
    res = loaded.analyses[0].run(loaded.model)
    np.testing.assert_allclose(res.body("bar").angle, 6.0 * res.t, rtol=0, atol=1e-12)
    # a field changed by path, as a sweep does: the motor's rate
    faster = read(path, {"joints.motor.motion.rate": 3.0})
    res = faster.analyses[0].run(faster.model)
    np.testing.assert_allclose(res.body("bar").angle, 3.0 * res.t, rtol=0, atol=1e-12)
    with pytest.raises(ModelFileError, match="no entry 'motr'"):
        read(path, {"joints.motr.motion.rate": 3.0})


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "tests"))
    write_model_files()


def test_primitive_shapes_give_mass_properties_and_round_trip(tmp_path):
    """A 0.2 x 0.1 x 0.05 m box of 1000 kg/m^3: 1 kg, I_zz = m (x^2 + y^2) / 12."""
    path = tmp_path / "box.yaml"
    path.write_text("""\
dim: 3
bodies:
  - {name: brick, shape: {box: [0.2, 0.1, 0.05]}, density: 1000.0, position: [0, 0, 1]}
""")
    model = mb.load(path)
    brick = model.body("brick")
    assert brick.mass == pytest.approx(1.0, rel=1e-12)
    assert brick.inertia[2, 2] == pytest.approx((0.2 ** 2 + 0.1 ** 2) / 12, rel=1e-12)
    again = mb.load(mb.save(model, tmp_path / "again.yaml"))
    assert "box: [0.2, 0.1, 0.05]" in (tmp_path / "again.yaml").read_text()
    np.testing.assert_array_equal(again.body("brick").inertia, brick.inertia)
    path.write_text(path.read_text().replace("box: [0.2, 0.1, 0.05]", "cylinder: [0.1]"))
    with pytest.raises(ModelFileError, match=r"box.yaml:3: bodies\[0\]: .*cylinder takes 2"):
        mb.load(path)


def test_saving_writes_only_inside_the_folder_and_replaces_nothing_unasked(tmp_path):
    """Mesh bodies are saved as <stem>.<body>.obj beside the model file: a body named like a
    path stays a file name there, and no file is replaced without overwrite=True (the
    mesh files neither), all checked before anything is written."""
    import trimesh
    b = mb.ModelBuilder(dim=3)
    names = ["sub/../../../x", "..", "plain"]
    for k, name in enumerate(names):
        b.add_body(name, shape=trimesh.creation.box((0.1, 0.2, 0.3 + 0.1 * k)), density=1000.0,
                   position=(k, 0.0, 0.0))
    model = b.build()
    folder = tmp_path / "deep" / "er"
    folder.mkdir(parents=True)
    path = mb.save(model, folder / "m.yaml")
    written = sorted(p.name for p in folder.iterdir())
    assert len(written) == 4 and "m.plain.obj" in written  # the file and three meshes
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file() and p.parent != folder) == []
    again = mb.load(path)
    for name in names:
        np.testing.assert_array_equal(again.body(name).inertia, model.body(name).inertia)
    # a second save replaces nothing, a mesh file left there neither
    before = {p: p.read_bytes() for p in folder.iterdir()}
    with pytest.raises(ModelFileError, match="already exists"):
        mb.save(model, folder / "m.yaml")
    (folder / "m.yaml").unlink()
    with pytest.raises(ModelFileError, match=r"\.obj' already exists"):
        mb.save(model, folder / "m.yaml")
    assert not (folder / "m.yaml").exists()
    assert {p: p.read_bytes() for p in folder.iterdir()} == {
        p: v for p, v in before.items() if p.name != "m.yaml"}
    mb.save(model, folder / "m.yaml", overwrite=True)
    assert mb.load(folder / "m.yaml").body("plain").mass == model.body("plain").mass


@pytest.mark.parametrize("content, message", [
    (b"\xff\xfe\x00\x01binary", r"m\.yaml:1: not UTF-8 text"),
    (GOOD.replace("name: pendulum", "name: caf\xe9").encode("latin-1"),
     r"m\.yaml:2: not UTF-8 text"),
    (GOOD.replace("dim: 2", "dim: 2.0").encode(), r"m\.yaml:3: dim: must be 2"),
    (GOOD.replace("points: 11", "points: -5").encode(),
     r"m\.yaml:14: analyses\[0\]\.t\.points: a whole number of output times"),
    (GOOD.replace("points: 11", "points: 2.5").encode(), r"t\.points: a whole number"),
    (GOOD.replace("stop: 1.0, points: 11", "stop: .inf, step: 0.1").encode(),
     r"analyses\[0\]\.t: times from 0.0 to inf by 0.1: need finite"),
    (GOOD.replace("stop: 1.0, points: 11", "stop: 1.0e9, step: 1.0e-9").encode(),
     r"analyses\[0\]\.t: that makes 1e\+18 output times"),
    (GOOD.replace("stop: 1.0, points: 11", "stop: 1.0, step: fast").encode(),
     r"analyses\[0\]\.t: start, stop and step are numbers"),
    (("[" * 5000 + "]" * 5000).encode(), r"m\.yaml.*(nested too deeply|not valid YAML)"),
])
def test_careless_files_are_refused_by_name_not_with_a_traceback(tmp_path, content, message):
    path = tmp_path / "m.yaml"
    path.write_bytes(content)
    with pytest.raises(ModelFileError, match=message):
        read(path)


def test_a_file_too_large_to_be_a_model_is_refused_before_it_is_read(tmp_path, monkeypatch):
    import mbd3d.io.model_file as model_file
    path = tmp_path / "m.yaml"
    path.write_text(GOOD)
    monkeypatch.setattr(model_file, "MAX_FILE_BYTES", len(GOOD) - 1)
    with pytest.raises(ModelFileError, match=r"m.yaml: 0 MB is not a model file"):
        read(path)
    monkeypatch.setattr(model_file, "MAX_FILE_BYTES", len(GOOD))
    assert read(path).model.name == "pendulum"
