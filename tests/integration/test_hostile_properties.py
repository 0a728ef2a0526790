"""Hostile input, generated (Hypothesis): scene documents, numbers and argument lists that nobody
wrote by hand, asserting only the contract. A scene either loads or is refused with SceneError
(never another exception type); a command either succeeds or prints one line `... error: ...`
with exit status 2, and never a traceback. A fixed budget of examples per test keeps this in the
fast tier (RESTIR_HYPOTHESIS_EXAMPLES=N runs N instead: 1500 scene documents and 600 argument
lists passed); the examples are derandomized, so a run is repeatable and a failure reproduces."""
import os
import string

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import restir
from restir.cli import main
from restir.config import ConfigError
from restir.scene.errors import SceneError

BUDGET = settings(max_examples=int(os.environ.get("RESTIR_HYPOTHESIS_EXAMPLES", "60")), deadline=None,
                  derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

# ------------------------------------------------------------------ scene documents
NUMBERS = st.one_of(st.sampled_from(["0", "-1", "1e308", "-1e308", "nan", "inf", "-inf", "1e-320", "", " ", "1,2",
                                     "0x10", "1e999", "--1", "3.5.1", "$x"]),
                    st.floats(allow_nan=True, allow_infinity=True).map(repr),
                    st.integers(-2**70, 2**70).map(str))
TEXT = st.text(string.ascii_letters + string.digits + " ._-/$", max_size=12)
PARAMS = st.builds(lambda tag, name, value: f'<{tag} name="{name}" value="{value}"/>',
                   st.sampled_from(["float", "integer", "boolean", "string", "rgb", "point", "vector"]),
                   st.sampled_from(["radius", "fov", "width", "height", "sample_count", "max_depth", "reflectance",
                                    "radiance", "alpha", "int_ior", "filename", "center", "scale", "x"]),
                   st.one_of(NUMBERS, TEXT))
TRANSFORMS = st.builds(lambda op, value: f'<transform name="to_world"><{op} value="{value}"/></transform>',
                       st.sampled_from(["scale", "translate", "rotate", "matrix", "lookat"]), NUMBERS)


def element(children):
    return st.builds(lambda tag, kind, inner: f'<{tag} type="{kind}">{"".join(inner)}</{tag}>',
                     st.sampled_from(["shape", "bsdf", "emitter", "texture", "sensor", "film", "sampler",
                                      "integrator", "rfilter"]),
                     st.sampled_from(["rectangle", "sphere", "cube", "disk", "obj", "ply", "diffuse", "conductor",
                                      "dielectric", "plastic", "roughplastic", "area", "constant", "envmap",
                                      "bitmap", "checkerboard", "perspective", "hdrfilm", "independent", "path",
                                      "gaussian", "box", "teapot"]),
                     st.lists(children, max_size=4))


ELEMENTS = st.recursive(st.one_of(PARAMS, TRANSFORMS), element, max_leaves=12)
DOCUMENTS = st.builds(lambda version, body: f'<scene version="{version}">{"".join(body)}</scene>',
                      st.sampled_from(["3.0.0", "0.6.0", "2.1.0", "x", "3"]), st.lists(ELEMENTS, max_size=5))


@BUDGET
@given(DOCUMENTS)
def test_a_generated_scene_loads_or_is_refused_with_a_scene_error(tmp_path_factory, document):
    path = tmp_path_factory.mktemp("scene") / "scene.xml"
    path.write_text(document)
    try:
        restir.load_scene(str(path))
    except SceneError as e:
        assert e.message and "\n" not in e.message


# ------------------------------------------------------------------ argument lists
HOSTILE_INTS = st.sampled_from(["-1", "0", "1", "3", "65537", "100000", "1000000000000", "1e3", "nan", "", "x"])
HOSTILE_FLOATS = st.sampled_from(["0", "-1", "0.5", "nan", "inf", "-inf", "1e309", "1e-320", "", "x"])
OPTIONS = st.one_of(
    st.tuples(st.sampled_from(["--width", "--height", "--spp", "--frames", "--max-depth", "--seed"]), HOSTILE_INTS),
    st.tuples(st.sampled_from(["--exposure", "--camera-speed"]), HOSTILE_FLOATS),
    st.tuples(st.just("--camera-motion"), st.sampled_from(["none", "orbit", "dolly", "spin", ""])),
    st.tuples(st.just("--method"), st.sampled_from(["pt", "restir-di", "restir-pt", "suffix-restir", "nope", ""])),
    st.tuples(st.just("--set"), st.sampled_from(["spp=2", "candidates=-1", "shift=nope", "=", "x", "rr=maybe"])),
    st.tuples(st.just("-D"), st.sampled_from(["a=1", "=", "noequals", "spp=nan"])),
    st.tuples(st.just("--tracer"), st.sampled_from(["auto", "warp", "embree", "optix"])),
)


@BUDGET
@given(st.lists(OPTIONS, max_size=4))
def test_generated_render_arguments_run_or_are_refused_in_one_line(tmp_path_factory, capsys, options):
    """Every render is kept tiny whatever the options say (a valid large film or spp would only be
    slow): the film is 4x4 unless an option overrides it with a hostile value that must be
    refused before any work."""
    args = ["render", "builtin:cornell-box", "--width", "4", "--height", "4", "--spp", "1", "--max-depth", "3",
            "--quiet", "-o", str(tmp_path_factory.mktemp("out") / "x.exr")]
    for option, value in options:
        if option in ("--width", "--height", "--spp") and value in ("65537", "100000"):
            value = "1000000000000"  # valid but slow: made certainly invalid
        args += [option, value]
    rc = main(args)
    out = capsys.readouterr()
    assert "Traceback" not in out.err + out.out, out.err
    if rc != 0:
        errors = [line for line in out.err.splitlines() if ": error: " in line]
        assert rc == 2 and len(errors) == 1, (args, rc, out.err)
        assert errors[0].startswith("restir render: error: ") or ": error: " in errors[0]


@pytest.mark.parametrize("field,value", [("width", 0), ("width", 10**9), ("height", -3), ("spp", 10**12),
                                         ("frames", 0), ("max_depth", 10**9), ("max_depth", -2),
                                         ("camera_speed", float("nan")), ("camera_speed", float("inf"))])
def test_the_api_raises_its_own_error_for_hostile_numbers(field, value):
    """The Python API: ConfigError, never numpy's or Warp's exceptions, before any allocation."""
    with pytest.raises(ConfigError):
        restir.render(restir.load_scene("builtin:cornell-box"), **{"width": 4, "height": 4, "spp": 1, field: value})


# The other commands, each at toy sizes unless a generated option says otherwise (with a value
# that is invalid or small): (command's arguments, its options)
COMMANDS = {
    "compare": (["compare", "builtin:cornell-box", "--method", "pt", "--frames", "2", "--warmup", "0",
                 "--reference-spp", "4", "--width", "4", "--height", "4", "--correlation-runs", "0", "--quiet"],
                st.one_of(st.tuples(st.sampled_from(["--frames", "--warmup", "--reference-spp", "--width",
                                                     "--correlation-runs", "--equal-spp", "--seed"]), HOSTILE_INTS),
                          st.tuples(st.just("--equal-time"), HOSTILE_FLOATS),
                          st.tuples(st.just("--method"), st.sampled_from(["restir-pt", "pt:spp=2", "pt:spp=x",
                                                                          "nope", ":", "pt:"])))),
    "validate": (["validate", "builtin:cornell-box", "--method", "pt", "--runs", "2", "--frames", "2", "--width", "4",
                  "--height", "4", "--ref-spp", "1"],
                 st.one_of(st.tuples(st.sampled_from(["--runs", "--ref-runs", "--frames", "--spp", "--width",
                                                      "--ref-spp"]), HOSTILE_INTS),
                           st.tuples(st.just("--max-mdb"), st.sampled_from(["0.05", "5%", "-1", "nan", "200%", "x"])),
                           st.tuples(st.just("--camera-speed"), HOSTILE_FLOATS))),
    "sweep": (["sweep", "builtin:cornell-box", "--method", "pt", "--frames", "2", "--warmup", "0", "--reference-spp",
               "4", "--width", "4", "--height", "4", "--quiet"],
              st.one_of(st.tuples(st.sampled_from(["--seeds", "--frames", "--spp", "--warmup", "--height"]),
                                  HOSTILE_INTS),
                        st.tuples(st.just("--grid"), st.sampled_from(["spp=1,2", "strategy=nee,bsdf", "nope=1",
                                                                      "spp=", "=1", "spp=nan"])))),
}


@settings(BUDGET, max_examples=max(1, BUDGET.max_examples // 4))
@given(st.sampled_from(sorted(COMMANDS)).flatmap(
    lambda name: st.tuples(st.just(name), st.lists(COMMANDS[name][1], max_size=3))))
def test_generated_arguments_of_every_command_run_or_are_refused_in_one_line(tmp_path_factory, capsys, monkeypatch,
                                                                            case):
    name, options = case
    folder = tmp_path_factory.mktemp(name)
    monkeypatch.setenv("RESTIR_CACHE", str(folder / "cache"))
    args = list(COMMANDS[name][0]) + (["--out", str(folder / "sweep")] if name == "sweep" else [])
    for option, value in options:
        args += [option, value]
    rc = main(args)
    out = capsys.readouterr()
    assert "Traceback" not in out.err + out.out, out.err
    assert rc in (0, 1, 2, 3), (args, rc, out.err)  # validate: 1 fail, 3 inconclusive
    if rc == 2:
        errors = [line for line in out.err.splitlines() if ": error: " in line]
        assert len(errors) == 1, (args, out.err)
