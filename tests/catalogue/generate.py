#!/usr/bin/env python3
"""Writes the catalogue of bad inputs (issue 15): the bad case files, recordings, NPY files,
audit specs and folders under tests/catalogue/, and the index catalogue.toml that
tests/catalogue.rs runs through the real binary.

    python3 tests/catalogue/generate.py

Every entry is one mistake a new user could plausibly make, applied to one of the valid base
cases (cases/base_*.toml, which tests/catalogue.rs runs too, to prove they are valid). The
`words` of an entry are what a GOOD error message must contain (case-insensitive): the culprit
(file, key, row, frame, node or value) and the reason. A word "a|b" is satisfied by either
alternative. The words are decided from the mistake, not copied from the binary's output.

Only the standard library is used (NPY files are written byte by byte).
"""
import math
import os
import shutil
import struct

HERE = os.path.dirname(os.path.abspath(__file__))

# ---------------------------------------------------------------------------------------------
# Base cases: each valid and fast (they are run by the test as a control).

BASE_STATIC = '''description = "catalogue base: static cantilever under a dead tip force (timoshenko_5pct, 20 elements)"

[constants]
L0 = 1e-3      # rod length [m]
F = 5e-9       # tip force [N]

[rod]
length_m = "L0"
elements = 20

[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = 5.0e4
shear_correction = "4/3"

[cross_section]
shape = "circle"
radius_m = "L0/40"

[loads]
end_force_n = [0, "-F", 0]

[solver]
analysis = "static"
method = "fixed_point"
quadrature = "selective"
relaxation = 0.5
tolerance = 1e-9
max_iterations = 200

[reference]
kind = "tip_loaded_cantilever"
force_n = "F"
'''

BASE_NEWTON = '''description = "catalogue base: static follower load by Newton with continuation (follower_bend_twist_65, 20 elements)"

[constants]
L0 = 1e-3
Fmax = 1e-4

[rod]
length_m = "L0"
elements = 20

[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = 5.0e4
shear_correction = "4/3"

[cross_section]
shape = "circle"
radius_m = "L0/40"

[loads]
frame = "local"
force_n_per_m = ["-2.2*Fmax", 0, 0]
torque_nm_per_m = ["1e-7", 0, 0]

[solver]
analysis = "static"
method = "newton"
quadrature = "selective"
tolerance = 1e-10
continuation_steps = 10
max_iterations = 30
'''

BASE_DYNAMIC = '''description = "catalogue base: dynamic cantilever (cantilever_dynamic, 10 elements, 20 steps)"

[constants]
omega0 = 207.0236   # first weak-axis bending frequency [1/s]

[rod]
length_m = 1.0
elements = 10

[material]
young_modulus_pa = 7.10e10
shear_modulus_pa = 2.69e10
density_kg_m3 = 2.73e3
shear_correction = 0.833

[cross_section]
shape = "rectangle"
width_m = 0.06
height_m = 0.04

[loads]
force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", "2e3*sin(pi*s)*sin(8*omega0*t)", 0]

[solver]
analysis = "dynamic"
method = "newton"
quadrature = "selective"
tolerance = 1e-12
max_iterations = 25

[time]
end_s = 0.006
steps = 20
'''

BASE_INVERSE = '''description = "catalogue base: inverse problem on synthetic data (inverse_bend, 20 elements)"

[constants]
L0 = 1e-3
Fmax = 1e-4

[rod]
length_m = "L0"
elements = 20

[material]
young_modulus_pa = 1.1e5
shear_modulus_pa = 5.0e4
shear_correction = "4/3"

[cross_section]
shape = "circle"
radius_m = "L0/40"

[loads]
frame = "local"
force_n_per_m = [0, "-Fmax*(exp(4*s/L0) - 1)/3", 0]

[data]
method = "newton"
tolerance = 1e-13
max_iterations = 40
continuation_steps = 5

[inverse]
lambda_g = 1e9
lambda_f = 1
lambda_l = 1e-10
lambda_d = 1e-6
lambda_kappa = [0, 0, 1e-10]

[solver]
analysis = "inverse"
method = "fixed_point"
relaxation = 0.5
tolerance = 1e-4
max_iterations = 1000
'''

BASE_INVERSE_NEWTON = BASE_INVERSE.replace(
    'description = "catalogue base: inverse problem on synthetic data (inverse_bend, 20 elements)"',
    'description = "catalogue base: inverse problem on synthetic data by Newton (inverse_bend, 20 elements)"',
).replace(
    'method = "fixed_point"\nrelaxation = 0.5\ntolerance = 1e-4\nmax_iterations = 1000',
    'method = "newton"\nrelaxation = 0.5\nwarm_start_tolerance = 1e-3\ntolerance = 1e-9\nmax_iterations = 200',
)


def clip_base(description, clip, elements=11):
    return f'''description = "{description}"

[constants]
L = 1e-3        # body length [m]
E = 1.1e5       # Young's modulus [Pa]

[rod]
length_m = "L"
elements = {elements}

[material]
young_modulus_pa = "E"
shear_modulus_pa = "E/(2*(1 + 0.4))"
shear_correction = "4/3"

[cross_section]
shape = "circle"
radius_m = 2e-5

[clip]
{clip}
[inverse]
lambda_g = 1e9
lambda_f = 1e-3
lambda_l = 1e-6
lambda_d = 1
lambda_kappa = [0, 0, 0]
lambda_omega = [0, 0, 1e-20]
stabilisation = 1e-3

[solver]
analysis = "inverse"
method = "fixed_point"
relaxation = 0.5
tolerance = 1e-6
max_iterations = 300
'''


def recording_clip(file):
    return f'''kind = "recording"
file = "{file}"
frame_interval_s = 0.04
min_cos_beta = 1e-3
start = "data_guess"
'''


BASE_RECORDING = clip_base(
    "catalogue base: inverse problem on a recorded clip (CSV, 3 frames x 12 nodes)",
    recording_clip("../recordings/good.csv"),
)
BASE_RECORDING_NPY = clip_base(
    "catalogue base: inverse problem on a recorded clip (NPY, 3 frames x 12 nodes x 3)",
    recording_clip("../recordings/good.npy"),
)
BASE_KYMOGRAM = clip_base(
    "catalogue base: inverse problem on a kymogram clip (NPY, 3 frames x 24 joint angles, 20 nodes)",
    '''kind = "kymogram"
file = "../recordings/kymogram_good.npy"
frame_interval_s = "1/32"
min_cos_beta = 1e-3
start = "data_guess"
''',
    elements=19,
)
BASE_ROLL = clip_base(
    "catalogue base: synthetic 3D clip (roll_3d) from a small kymogram (3 frames, 20 nodes)",
    '''kind = "roll_3d"
file = "../recordings/kymogram_good.npy"
frame_interval_s = 0.04
clip_frames = 3
roll_total_rad = "pi/2"
twist_per_m = 500
min_cos_beta = 1e-2
start = "previous_frame"
''',
    elements=19,
)

BASES = {
    "base_static": BASE_STATIC,
    "base_newton": BASE_NEWTON,
    "base_dynamic": BASE_DYNAMIC,
    "base_inverse": BASE_INVERSE,
    "base_inverse_newton": BASE_INVERSE_NEWTON,
    "base_recording": BASE_RECORDING,
    "base_recording_npy": BASE_RECORDING_NPY,
    "base_kymogram": BASE_KYMOGRAM,
    "base_roll": BASE_ROLL,
}

# ---------------------------------------------------------------------------------------------
# Recordings: 3 frames of 12 nodes on a body of 1 mm, planar arcs of growing curvature.

NODES = 12
LENGTH = 1e-3


def arc(k, n=NODES, length=LENGTH):
    pts = []
    for i in range(n):
        s = length * i / (n - 1)
        pts.append(((1 - math.cos(k * s)) / k, 0.0, math.sin(k * s) / k))
    return pts


GOOD_FRAMES = [arc(k) for k in (400.0, 600.0, 800.0)]


def csv_rows(frames):
    return [(f, i, *p) for f, pts in enumerate(frames) for i, p in enumerate(pts)]


def csv_text(rows, header="frame,node,x_m,y_m,z_m", sep=","):
    lines = [header] if header is not None else []
    for r in rows:
        lines.append(sep.join(str(v) if isinstance(v, str) else (f"{v}" if isinstance(v, int) else f"{v:.17e}") for v in r))
    return "\n".join(lines) + "\n"


def npy_bytes(shape, data, descr="<f8", fortran=False, fmt="<d", version=1):
    dims = f"({shape[0]},)" if len(shape) == 1 else "(" + ", ".join(str(n) for n in shape) + ")"
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (descr, "True" if fortran else "False", dims)
    pre = 6 + 2 + (2 if version == 1 else 4)
    unpadded = pre + len(header) + 1
    header += " " * ((64 - unpadded % 64) % 64) + "\n"
    out = b"\x93NUMPY" + bytes([version, 0])
    out += struct.pack("<H" if version == 1 else "<I", len(header))
    out += header.encode()
    for v in data:
        out += struct.pack(fmt, v)
    return out


def flat(frames):
    return [c for pts in frames for p in pts for c in p]


def kymogram_rows(frames=3, joints=24, amp=0.3):
    return [[amp * math.sin(2 * math.pi * j / joints + 0.5 * f) for j in range(joints)] for f in range(frames)]


# ---------------------------------------------------------------------------------------------
# The catalogue.

FILES = {}  # relative path -> bytes or str
ENTRIES = []


def put(path, content):
    assert path not in FILES, f"{path} written twice"
    FILES[path] = content


def entry(id, kind, args, words, what, stdin=None, files=None):
    assert not any(e["id"] == id for e in ENTRIES), f"duplicate id {id}"
    assert words, id
    ENTRIES.append(dict(id=id, kind=kind, what=what, args=args, words=words, stdin=stdin, files=files))


def edit(text, old, new):
    assert text.count(old) == 1, f"`{old}` occurs {text.count(old)} times"
    return text.replace(old, new, 1)


def drop_line(text, line):
    return edit(text, line + "\n", "")


def case(id, base, edits, words, what, kind="case", cmd="run", extra=None, name=None, file_word=True):
    """A case file `cases/<id>.toml`: `base` with `edits` applied ((old, new) replacements;
    new None deletes the line `old`; a str is appended). The file name is a word."""
    text = BASES[base]
    for e in edits:
        if isinstance(e, str):
            text += e
        elif e[1] is None:
            text = drop_line(text, e[0])
        else:
            text = edit(text, e[0], e[1])
    fname = f"{name or id}.toml"
    put(f"cases/{fname}", text)
    args = [cmd, "{cat}/cases/" + fname]
    if cmd == "run":
        args += ["--out", "{out}", "--quiet"]
    args += extra or []
    entry(id, kind, args, ([fname] if file_word else []) + words, what)


def line_of(text, needle):
    for i, l in enumerate(text.split("\n")):
        if needle in l:
            return i + 1
    raise AssertionError(needle)


def syntax(id, base, old, new, words, what, needle=None):
    """A TOML syntax error: the message names the line of `needle` (default: the new text)."""
    text = edit(BASES[base], old, new)
    line = line_of(text, needle or new)
    case(id, base, [(old, new)], [f"line {line}"] + words, what)


# the base cases as files stop their quick fixed points early: held to the certificate such a stop
# leaves (the entries built on them fail before any solve and keep the default)
QUICK_CERTIFICATE = {"base_inverse": "1e-4", "base_kymogram": "1e-7", "base_recording": "1e-7",
                     "base_recording_npy": "1e-7", "base_roll": "1e-8"}
for name, text in BASES.items():
    if name in QUICK_CERTIFICATE:
        text += ("# a quick base case: the fixed point stopped early, held to the certificate such a stop leaves\n"
                 f"certificate_tolerance = {QUICK_CERTIFICATE[name]}\n")
    put(f"cases/{name}.toml", text)

POS = "> 0|positive|greater than 0|greater than zero|must be >"
COUNT = "≥ 1|>= 1|at least 1|> 0|positive|at least one"
UNKNOWN = "unknown|not a key|unexpected|not allowed|no such key"
MISSING = "missing|required"
NOT_FINITE = "not finite|non-finite|nan|infinite|overflow"
MEMORY = "memory|too many|too large|at most|exceeds|limit"
NO_FILE = "no such file|does not exist|not found"

# --- TOML syntax ---------------------------------------------------------------------------
syntax("toml_unclosed_string", "base_static", 'shape = "circle"', 'shape = "circle', [],
       "a string without its closing quote")
syntax("toml_missing_equals", "base_static", "elements = 20", "elements 20", [],
       "a key and its value without `=`")
case("toml_duplicate_key", "base_static", [("elements = 20", "elements = 20\nelements = 40")],
     ["elements", "duplicate|twice|defined"], "the same key twice in [rod]")
case("toml_duplicate_table", "base_static", ["\n[rod]\nelements = 40\n"],
     ["rod", "duplicate|twice|defined"], "a second [rod] table at the end of the file")
syntax("toml_unclosed_array", "base_static", 'end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-F", 0',
       [], "an array without its closing bracket")
syntax("toml_bad_number", "base_static", "tolerance = 1e-9", "tolerance = 1e-9e", [], "a malformed number")
syntax("toml_decimal_comma", "base_static", "young_modulus_pa = 1.1e5", "young_modulus_pa = 1,1e5", [],
       "a decimal comma (European locale)")
syntax("toml_unicode_minus", "base_static", "tolerance = 1e-9", "tolerance = 1e\u22129", [],
       "a Unicode minus sign pasted from the paper into a TOML number")
syntax("toml_unquoted_expression", "base_static", 'radius_m = "L0/40"', "radius_m = L0/40", [],
       "an expression of the constants without quotes")
syntax("toml_python_bool", "base_static", "end_force_n", "fixed = True\nend_force_n", [],
       "Python's True for a TOML boolean", needle="fixed = True")
put("cases/toml_json.toml", '{"description": "json", "rod": {"length_m": 1e-3, "elements": 20}}\n')
entry("toml_json", "case", ["run", "{cat}/cases/toml_json.toml", "--out", "{out}", "--quiet"],
      ["toml_json.toml", "line 1"], "a JSON file given as the case")
put("cases/toml_empty.toml", "")
entry("toml_empty", "case", ["run", "{cat}/cases/toml_empty.toml", "--out", "{out}", "--quiet"],
      ["toml_empty.toml", "empty"], "an empty case file")
put("cases/toml_utf16.toml", b"\xff\xfe" + BASE_STATIC.encode("utf-16-le"))
entry("toml_utf16", "case", ["run", "{cat}/cases/toml_utf16.toml", "--out", "{out}", "--quiet"],
      ["toml_utf16.toml", "utf-8|utf8|utf-16|encoding"], "a case saved as UTF-16 by a Windows editor")

# --- unknown keys and values ---------------------------------------------------------------
case("unknown_top_key", "base_static", [('description =', 'descripton =')], ["descripton", UNKNOWN],
     "a misspelt top-level key")
case("unknown_rod_key", "base_static", [('length_m = "L0"', 'length = "L0"')], ["length", UNKNOWN],
     "`length` without its unit suffix _m")
case("unknown_material_key", "base_static", [("shear_modulus_pa = 5.0e4", "shear_modulus_pa = 5.0e4\npoisson_ratio = 0.4")],
     ["poisson_ratio", UNKNOWN], "a Poisson ratio, which the case format does not take")
case("unknown_youngs", "base_static", [("young_modulus_pa = 1.1e5", "youngs_modulus_pa = 1.1e5")],
     ["youngs_modulus_pa", UNKNOWN], "`youngs_modulus_pa` for young_modulus_pa")
case("unknown_table", "base_static", [("[solver]", "[solvers]")], ["solvers", UNKNOWN], "[solvers] for [solver]")
case("unknown_loads_key", "base_static", [("end_force_n =", "tip_force_n =")], ["tip_force_n", UNKNOWN],
     "`tip_force_n` for end_force_n")
case("unknown_solver_key", "base_static", [("max_iterations = 200", "max_iter = 200")], ["max_iter", UNKNOWN],
     "`max_iter` for max_iterations")
case("unknown_time_key", "base_dynamic", [("steps = 20", "dt = 3e-4")], ["dt", UNKNOWN],
     "a time step `dt` for [time] steps")
case("unknown_clip_key", "base_recording", [("frame_interval_s = 0.04", "fps = 25")], ["fps", UNKNOWN],
     "frames per second for clip.frame_interval_s")
case("unknown_inverse_key", "base_inverse", [("lambda_kappa = [0, 0, 1e-10]", "lambda_k = [0, 0, 1e-10]")],
     ["lambda_k", UNKNOWN], "`lambda_k` for lambda_kappa")
case("unknown_section_key", "base_static", [('radius_m = "L0/40"', 'diameter_m = "L0/20"')],
     ["diameter_m", UNKNOWN], "a diameter for the circle's radius")
case("bad_analysis", "base_static", [('analysis = "static"', 'analysis = "statics"')],
     ["analysis", "statics"], "a misspelt analysis")
case("bad_method_case", "base_static", [('method = "fixed_point"', 'method = "Fixed_Point"')],
     ["method", "Fixed_Point"], "a method in the wrong case")
case("bad_shape", "base_static", [('shape = "circle"', 'shape = "square"')], ["shape", "square"],
     "a cross-section shape that does not exist")
case("bad_quadrature", "base_static", [('quadrature = "selective"', 'quadrature = "gauss"')],
     ["quadrature", "gauss"], "an unknown quadrature")
case("bad_load_frame", "base_newton", [('frame = "local"', 'frame = "follower"')], ["frame", "follower"],
     "`follower` for the local load frame")
case("bad_clip_kind", "base_recording", [('kind = "recording"', 'kind = "csv"')], ["kind", "csv"],
     "the file format for the clip kind")
case("bad_clip_start", "base_recording", [('start = "data_guess"', 'start = "previous"')], ["start", "previous"],
     "an unknown clip start")
case("bad_reference_kind", "base_static", [('kind = "tip_loaded_cantilever"', 'kind = "cantilever"')],
     ["kind", "cantilever"], "an unknown reference kind")
case("bad_clip_plane", "base_kymogram", [('start = "data_guess"', 'start = "data_guess"\nplane = "yz"')],
     ["plane", "yz"], "a placement plane that does not exist")

# --- wrong types -------------------------------------------------------------------------------
case("type_elements_float", "base_static", [("elements = 20", "elements = 20.5")], ["elements", "20.5", "integer"],
     "a fractional element count")
case("type_elements_string", "base_static", [("elements = 20", 'elements = "20"')], ["elements", "integer"],
     "an element count in quotes")
case("type_elements_negative", "base_static", [("elements = 20", "elements = -5")], ["elements", "-5"],
     "a negative element count")
case("type_length_bool", "base_static", [('length_m = "L0"', "length_m = true")], ["length_m", "number"],
     "a boolean for the rod length")
case("type_force_scalar", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = "-F"')],
     ["end_force_n", "array|vector|3 components|three"], "a scalar where a 3-vector is expected")
case("type_force_two", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-F"]')],
     ["end_force_n", "length 3|3 components|3 entries|3 values|3 elements|three"], "a 3-vector with two components")
case("type_rod_value", "base_static", [('[rod]\nlength_m = "L0"\nelements = 20\n', 'rod = 1e-3\n')],
     ["rod", "table"], "`rod = 1e-3` instead of a [rod] table")
case("type_description_number", "base_static",
     [('description = "catalogue base: static cantilever under a dead tip force (timoshenko_5pct, 20 elements)"',
       "description = 5")], ["description", "string|text"], "a number for the description")
case("type_frames_string", "base_recording", [("min_cos_beta", 'frames = [0, "2"]\nmin_cos_beta')],
     ["frames", "integer"], "a clip frame range with a quoted end")
case("type_lambda_kappa_scalar", "base_inverse", [("lambda_kappa = [0, 0, 1e-10]", "lambda_kappa = 1e-10")],
     ["lambda_kappa", "array|vector|3 components|three"], "a scalar for the three curvature weights")
case("type_continuation_float", "base_newton", [("continuation_steps = 10", "continuation_steps = 2.5")],
     ["continuation_steps", "2.5", "integer"], "a fractional continuation step count")

# --- missing required keys -----------------------------------------------------------------------
case("missing_description", "base_static",
     [('description = "catalogue base: static cantilever under a dead tip force (timoshenko_5pct, 20 elements)"', None)],
     ["description", MISSING], "no description")
case("missing_rod", "base_static", [('[rod]\nlength_m = "L0"\nelements = 20\n', "")], ["rod", MISSING], "no [rod] table")
case("missing_length", "base_static", [('length_m = "L0"', None)], ["length_m", MISSING], "no rod length")
case("missing_elements", "base_static", [("elements = 20", None)], ["elements", MISSING], "no element count")
case("missing_young", "base_static", [("young_modulus_pa = 1.1e5", None)], ["young_modulus_pa", MISSING],
     "no Young's modulus")
case("missing_shear_modulus", "base_static", [("shear_modulus_pa = 5.0e4", None)], ["shear_modulus_pa", MISSING],
     "no shear modulus")
case("missing_shear_correction", "base_static", [('shear_correction = "4/3"', None)],
     ["shear_correction", MISSING], "no shear correction factor")
case("missing_radius", "base_static", [('radius_m = "L0/40"', None)], ["radius_m", MISSING], "a circle without radius")
case("missing_height", "base_dynamic", [("height_m = 0.04", None)], ["height_m", MISSING],
     "a rectangle without height")
case("missing_shape", "base_static", [('shape = "circle"', None)], ["shape", MISSING], "a cross-section without shape")
case("missing_analysis", "base_static", [('analysis = "static"', None)], ["analysis", MISSING], "no analysis")
case("missing_tolerance", "base_static", [("tolerance = 1e-9", None)], ["tolerance", MISSING], "no tolerance")
case("missing_max_iterations", "base_static", [("max_iterations = 200", None)], ["max_iterations", MISSING],
     "no iteration limit")
case("missing_relaxation", "base_static", [("relaxation = 0.5", None)], ["relaxation", MISSING],
     "a fixed point without relaxation")
case("missing_time", "base_dynamic", [("[time]\nend_s = 0.006\nsteps = 20\n", "")], ["time", MISSING],
     "a dynamic analysis without [time]")
case("missing_steps", "base_dynamic", [("steps = 20", None)], ["steps", MISSING], "[time] without steps")
case("missing_density_dynamic", "base_dynamic", [("density_kg_m3 = 2.73e3", None)], ["density_kg_m3", MISSING],
     "a dynamic analysis without density")
case("missing_inverse_table", "base_inverse",
     [("[inverse]\nlambda_g = 1e9\nlambda_f = 1\nlambda_l = 1e-10\nlambda_d = 1e-6\nlambda_kappa = [0, 0, 1e-10]\n", "")],
     ["inverse", MISSING], "an inverse analysis without its weights")
case("missing_data_and_clip", "base_inverse",
     [("[data]\nmethod = \"newton\"\ntolerance = 1e-13\nmax_iterations = 40\ncontinuation_steps = 5\n", "")],
     ["data", "clip"], "an inverse analysis with neither [data] nor [clip]")
case("missing_warm_start", "base_inverse_newton", [("warm_start_tolerance = 1e-3", None)],
     ["warm_start_tolerance", MISSING], "inverse Newton without its warm-start tolerance")
case("missing_clip_file", "base_recording", [('file = "../recordings/good.csv"', None)], ["file", MISSING],
     "a clip without file")
case("missing_frame_interval", "base_recording", [("frame_interval_s = 0.04", None)],
     ["frame_interval_s", MISSING], "a clip without frame interval")

# --- out-of-range physical values ----------------------------------------------------------------
case("range_length_negative", "base_static", [('length_m = "L0"', "length_m = -1e-3")],
     ["length_m", "-0.001|-1e-3", POS], "a negative rod length")
case("range_length_zero", "base_static", [('length_m = "L0"', "length_m = 0")], ["length_m", POS], "a zero rod length")
case("range_radius_zero", "base_static", [('radius_m = "L0/40"', "radius_m = 0")], ["radius_m", POS], "a zero radius")
case("range_radius_negative", "base_static", [('radius_m = "L0/40"', 'radius_m = "-L0/40"')],
     ["radius_m", "-2.5e-5|-0.000025", POS], "a negative radius")
case("range_width_zero", "base_dynamic", [("width_m = 0.06", "width_m = 0")], ["width_m", POS], "a zero width")
case("range_young_zero", "base_static", [("young_modulus_pa = 1.1e5", "young_modulus_pa = 0")],
     ["young_modulus_pa", POS], "a zero Young's modulus")
case("range_young_negative", "base_static", [("young_modulus_pa = 1.1e5", "young_modulus_pa = -1.1e5")],
     ["young_modulus_pa", "-110000|-1.1e5", POS], "a negative Young's modulus")
case("range_shear_zero", "base_static", [("shear_modulus_pa = 5.0e4", "shear_modulus_pa = 0")],
     ["shear_modulus_pa", POS], "a zero shear modulus")
case("range_shear_correction_negative", "base_static", [('shear_correction = "4/3"', 'shear_correction = "-4/3"')],
     ["shear_correction", POS], "a negative shear correction")
case("range_density_zero", "base_dynamic", [("density_kg_m3 = 2.73e3", "density_kg_m3 = 0")],
     ["density_kg_m3", POS], "a zero density")
case("range_density_negative", "base_dynamic", [("density_kg_m3 = 2.73e3", "density_kg_m3 = -2.73e3")],
     ["density_kg_m3", "-2730|-2.73e3", POS], "a negative density")
case("range_elements_zero", "base_static", [("elements = 20", "elements = 0")],
     ["elements", "at least|≥|>=|> 0|positive"], "no elements")
case("range_elements_huge", "base_static", [("elements = 20", "elements = 10000000")],
     ["elements", "10000000", MEMORY], "10 million elements (a typo of 100)")
case("range_elements_huge_dynamic", "base_dynamic", [("elements = 10", "elements = 10000000")],
     ["elements", "10000000", MEMORY], "10 million elements in a dynamic run")
case("range_elements_1e12", "base_static", [("elements = 20", "elements = 1000000000000")],
     ["elements", "1000000000000", MEMORY], "a trillion elements")
case("range_tolerance_zero", "base_static", [("tolerance = 1e-9", "tolerance = 0")],
     ["tolerance", "> 0|positive|(0, 1)|greater than"], "a zero tolerance")
case("range_tolerance_negative", "base_static", [("tolerance = 1e-9", "tolerance = -1e-9")],
     ["tolerance", "-1e-9|-0.000000001", "> 0|positive|(0, 1)|greater than"], "a negative tolerance")
case("range_tolerance_above_one", "base_static", [("tolerance = 1e-9", "tolerance = 1.5")],
     ["tolerance", "1.5", "(0, 1)|< 1|less than 1|below 1"], "a tolerance of 150 %")
case("range_max_iterations_zero", "base_static", [("max_iterations = 200", "max_iterations = 0")],
     ["max_iterations", COUNT], "no iterations allowed")
case("range_steps_zero", "base_dynamic", [("steps = 20", "steps = 0")], ["steps", COUNT], "no time steps")
case("range_end_zero", "base_dynamic", [("end_s = 0.006", "end_s = 0")], ["end_s", POS], "a zero end time (Δt = 0)")
case("range_end_negative", "base_dynamic", [("end_s = 0.006", "end_s = -0.006")], ["end_s", "-0.006", POS],
     "a negative end time (Δt < 0)")
case("range_frame_interval_zero", "base_recording", [("frame_interval_s = 0.04", "frame_interval_s = 0")],
     ["frame_interval_s", POS], "a zero frame interval")
case("range_frame_interval_negative", "base_kymogram", [('frame_interval_s = "1/32"', 'frame_interval_s = "-1/32"')],
     ["frame_interval_s", "-0.03125", POS], "a negative frame interval")
case("range_relaxation_zero", "base_static", [("relaxation = 0.5", "relaxation = 0")],
     ["relaxation", "(0, 1]|> 0|positive"], "a zero relaxation")
case("range_relaxation_above_one", "base_static", [("relaxation = 0.5", "relaxation = 1.5")],
     ["relaxation", "1.5", "(0, 1]|≤ 1|<= 1|at most 1"], "an over-relaxation of 1.5")
case("range_continuation_zero", "base_newton", [("continuation_steps = 10", "continuation_steps = 0")],
     ["continuation_steps", COUNT], "zero continuation steps")
case("range_lambda_g_zero", "base_inverse", [("lambda_g = 1e9", "lambda_g = 0")], ["lambda_g", POS],
     "a zero data weight")
case("range_lambda_d_negative", "base_inverse", [("lambda_d = 1e-6", "lambda_d = -1e-6")],
     ["lambda_d", "≥ 0|>= 0|non-negative|nonnegative"], "a negative weight")
case("range_stabilisation", "base_recording", [("stabilisation = 1e-3", "stabilisation = 2")],
     ["stabilisation", "2", "[0, 1]|≤ 1|<= 1|at most 1"], "a stabilisation above 1")
case("range_min_cos_beta", "base_recording", [("min_cos_beta = 1e-3", "min_cos_beta = 1")],
     ["min_cos_beta", "[0, 1)|< 1|less than 1"], "a chart guard of 1 that stops every frame")
case("range_frames_reversed", "base_recording", [("min_cos_beta", "frames = [2, 0]\nmin_cos_beta")],
     ["frames", "[2, 0]|first < end|first"], "a frame range backwards")
case("range_frames_beyond_clip", "base_recording", [("min_cos_beta", "frames = [0, 1000]\nmin_cos_beta")],
     ["frames", "1000", "3 frames|has 3|only 3"], "a frame range past the 3 frames of the recording")
case("range_compare_frames_zero", "base_recording", ["\n[compare]\nframes = 0\n"], ["compare.frames|frames", COUNT],
     "zero frames to compare")
case("range_data_max_iterations", "base_inverse", [("max_iterations = 40", "max_iterations = 0")],
     ["data.max_iterations", COUNT], "zero iterations for the forward data solve")
case("range_data_tolerance", "base_inverse", [("tolerance = 1e-13", "tolerance = 0")],
     ["data.tolerance", "> 0|positive|(0, 1)"], "a zero tolerance for the forward data solve")
case("range_warm_start_zero", "base_inverse_newton", [("warm_start_tolerance = 1e-3", "warm_start_tolerance = 0")],
     ["warm_start_tolerance", "> 0|positive|(0, 1)"], "a zero warm-start tolerance")
case("range_gauge_zero", "base_recording", [("min_cos_beta = 1e-3", "min_cos_beta = 1e-3\ngauge = [0, 0, 0]")],
     ["gauge", "zero|non-zero|nonzero"], "a zero gauge vector")
case("range_orientation_nan", "base_recording", [("min_cos_beta = 1e-3", "min_cos_beta = 1e-3\norientation = [nan, 0, 0]")],
     ["orientation", "nan|finite"], "a NaN in the orientation (TOML `nan`)")
case("range_young_nan", "base_static", [("young_modulus_pa = 1.1e5", "young_modulus_pa = nan")],
     ["young_modulus_pa", "nan|finite"], "Young's modulus `nan` (a TOML float)")
case("range_length_inf", "base_static", [('length_m = "L0"', "length_m = inf")], ["length_m", "inf|finite"],
     "an infinite rod length (TOML `inf`)")
case("range_tolerance_nan", "base_static", [("tolerance = 1e-9", "tolerance = nan")], ["tolerance", "nan|finite"],
     "a NaN tolerance")
case("range_lambda_f_inf", "base_inverse", [("lambda_f = 1", "lambda_f = inf")], ["lambda_f", "inf|finite"],
     "an infinite force weight")
case("range_buckling_modes_zero", "base_newton", [("continuation_steps = 10", "continuation_steps = 10\nbuckling_modes = 0")],
     ["buckling_modes", COUNT], "zero buckling modes asked for")
case("contra_buckling_modes_dynamic", "base_dynamic", [("max_iterations = 25", "max_iterations = 25\nbuckling_modes = 2")],
     ["buckling_modes", "static"], "buckling modes of a dynamic analysis")
case("range_substeps_zero", "base_roll", [("clip_frames = 3", "clip_frames = 3\nsubsteps = 0")],
     ["substeps", COUNT], "zero integration substeps of a synthetic clip")
case("range_steps_huge", "base_dynamic", [("steps = 20", "steps = 1000000000000")],
     ["steps", "1000000000000", MEMORY], "a trillion time steps (the tip history alone is 24 TB)")
case("range_clip_frames_huge", "base_roll", [("clip_frames = 3", "clip_frames = 1000000000000")],
     ["clip_frames", "1000000000000", MEMORY], "a trillion synthetic frames")

# --- contradictory settings -----------------------------------------------------------------------
case("contra_static_with_time", "base_static", ["\n[time]\nend_s = 1\nsteps = 10\n"], ["time", "dynamic"],
     "a [time] table on a static analysis")
case("contra_dynamic_fixed_point", "base_dynamic", [('method = "newton"', 'method = "fixed_point"')],
     ["method", "newton"], "a dynamic analysis by fixed point")
case("contra_dynamic_relaxation", "base_dynamic", [("tolerance = 1e-12", "relaxation = 0.5\ntolerance = 1e-12")],
     ["relaxation", "dynamic"], "a relaxation on a dynamic analysis")
case("contra_newton_relaxation", "base_newton", [("tolerance = 1e-10", "relaxation = 0.5\ntolerance = 1e-10")],
     ["relaxation", "newton"], "a relaxation with method = newton")
case("contra_static_inverse_table", "base_static",
     ["\n[inverse]\nlambda_g = 1e9\nlambda_f = 1\nlambda_l = 1e-10\nlambda_d = 1e-6\nlambda_kappa = [0, 0, 0]\n"],
     ["inverse", "analysis"], "inverse weights on a static analysis")
case("contra_data_and_clip", "base_recording",
     [("[inverse]", "[data]\nmethod = \"newton\"\ntolerance = 1e-13\nmax_iterations = 40\n\n[inverse]")],
     ["data", "clip"], "both [data] and [clip]")
case("contra_warm_start_fixed_point", "base_inverse", [("relaxation = 0.5", "relaxation = 0.5\nwarm_start_tolerance = 1e-3")],
     ["warm_start_tolerance", "newton"], "a warm-start tolerance with the fixed point")
case("contra_dynamic_continuation", "base_dynamic", [("max_iterations = 25", "max_iterations = 25\ncontinuation_steps = 5")],
     ["continuation_steps", "static"], "continuation steps on a dynamic analysis")
case("contra_two_frame_intervals", "base_recording", [("stabilisation = 1e-3", "stabilisation = 1e-3\nframe_interval_s = 0.04")],
     ["frame_interval_s", "clip"], "Δt in both [inverse] and [clip]")
case("contra_reference_dynamic", "base_dynamic", ['\n[reference]\nkind = "tip_loaded_cantilever"\nforce_n = 1\n'],
     ["reference", "static"], "a static reference on a dynamic analysis")
case("contra_roll_keys_on_recording", "base_recording", [("min_cos_beta = 1e-3", "min_cos_beta = 1e-3\nclip_frames = 10")],
     ["clip_frames", "roll_3d"], "a roll_3d key on a recording")
case("contra_omega_without_dt", "base_inverse", [("lambda_kappa = [0, 0, 1e-10]", "lambda_kappa = [0, 0, 1e-10]\nlambda_omega = [0, 0, 1e-6]")],
     ["frame_interval_s", "lambda_omega"], "a time-smoothing weight without a frame interval")
case("contra_compare_without_reason", "base_static", ["\n[compare]\ndisplacement_rel = 1e-3\n"],
     ["displacement_rel", "reason"], "a tolerance override without a reason")
case("contra_reference_force_mismatch", "base_static", [('force_n = "F"', 'force_n = "2*F"')],
     ["reference.force_n|force_n", "end_force_n"],
     "the reference's force (2F) is not the tip load (F): the theory errors in metrics.json are against another load")
PUBLISHED = ('\n[[reference.values]]\nquantity = "tip.y_m"\nvalue = "-0.05*L0"\ntolerance_abs = "1e-3*L0"\n'
             'source = "A. Author (2000), J. Rods 1, Table 1"\n')
case("published_unknown_quantity", "base_static", [PUBLISHED.replace("tip.y_m", "tip.deflection_m")],
     ["reference.values[0].quantity", "deflection_m", "tip.displacement_y_m"],
     "a published value of a quantity that is not in the vocabulary")
case("published_without_source", "base_static", [PUBLISHED.replace('source = "A. Author (2000), J. Rods 1, Table 1"\n', "")],
     ["reference.values[0].source", "source"], "a published value without its source")
case("published_two_tolerances", "base_static",
     [PUBLISHED.replace('tolerance_abs = "1e-3*L0"', 'tolerance_abs = "1e-3*L0"\ntolerance_rel = 0.01')],
     ["reference.values[0]", "tolerance_abs", "tolerance_rel"], "a published value with two tolerances")
case("published_metric_not_written", "base_static", [PUBLISHED.replace("tip.y_m", "metric.tip_max_abs_y_m")],
     ["reference.values[0]", "tip_max_abs_y_m"], "a published metric that a static run does not write")
case("contra_kymogram_on_static", "base_static",
     ['\n[clip]\nkind = "kymogram"\nfile = "../recordings/kymogram_good.npy"\nframe_interval_s = 0.04\nmin_cos_beta = 1e-3\n'],
     ["clip", "inverse"], "a [clip] table on a static analysis")

# --- expressions (constants and loads) ---------------------------------------------------------------
EXPR_BAD = "cannot parse|unexpected|expected|invalid|syntax"
case("expr_unclosed_paren", "base_dynamic",
     [('force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", ', 'force_n_per_m = ["2e3*sin(pi*s*sin(8*omega0*t)", ')],
     ["force_n_per_m", "2e3*sin(pi*s*sin(8*omega0*t)", EXPR_BAD], "an unclosed parenthesis", kind="expression")
case("expr_unknown_function", "base_dynamic",
     [('force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", ', 'force_n_per_m = ["2e3*sine(pi*s)*sin(8*omega0*t)", ')],
     ["force_n_per_m", "sine", "unknown"], "`sine` for sin", kind="expression")
case("expr_unknown_name", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-F2", 0]')],
     ["end_force_n", "F2", "unknown"], "a constant that is not defined", kind="expression")
case("expr_case_sensitive_name", "base_static", [('radius_m = "L0/40"', 'radius_m = "l0/40"')],
     ["radius_m", "l0", "unknown"], "`l0` for the constant L0", kind="expression")
case("expr_nan_string", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "nan", 0]')],
     ["end_force_n", "nan"], "`nan` as a load", kind="expression")
case("expr_inf_string", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-inf", 0]')],
     ["end_force_n", "inf"], "`-inf` as a load", kind="expression")
case("expr_division_by_zero_load", "base_newton", [('force_n_per_m = ["-2.2*Fmax", 0, 0]', 'force_n_per_m = ["1/(s-s)", 0, 0]')],
     ["force_n_per_m", "1/(s-s)", NOT_FINITE + "|division by zero"], "a load that is 0/0 everywhere", kind="expression")
case("expr_singular_at_clamp", "base_newton", [('force_n_per_m = ["-2.2*Fmax", 0, 0]', 'force_n_per_m = ["-1e-9/s", 0, 0]')],
     ["force_n_per_m", "s = 0|s=0|" + NOT_FINITE], "a distributed load infinite at the clamp (1/s)", kind="expression")
case("expr_huge_end_load", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-5e300", 0]')],
     ["end_force_n", "5e300|5e+300", NOT_FINITE + "|too large|diverge|another load"], "an end force of 5e300 N on a 1 mm rod",
     kind="expression")
case("expr_huge_distributed_load", "base_newton", [('force_n_per_m = ["-2.2*Fmax", 0, 0]', 'force_n_per_m = ["5e300", 0, 0]')],
     ["force_n_per_m", "5e300|5e+300", NOT_FINITE + "|too large|diverge"], "a distributed force of 5e300 N/m",
     kind="expression")
case("expr_dynamic_overflow", "base_dynamic",
     [('force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", ', 'force_n_per_m = ["2e3*exp(1e5*t)", ')],
     ["force_n_per_m", "t =|time|step", "diverged|" + NOT_FINITE],
     "a load growing as 2e3 exp(1e5 t), to 7.5e263 N/m within the run (finite, but far beyond the rod)", kind="expression")
case("expr_sqrt_negative", "base_static", [('radius_m = "L0/40"', 'radius_m = "sqrt(-L0)"')],
     ["radius_m", "nan|finite"], "the square root of a negative number", kind="expression")
case("expr_log_zero", "base_static", [("shear_modulus_pa = 5.0e4", 'shear_modulus_pa = "5e4*log(0)"')],
     ["shear_modulus_pa", "inf|finite"], "log(0)", kind="expression")
case("expr_constant_div_zero", "base_static", [("F = 5e-9       # tip force [N]", 'F = "5e-9/0"')],
     ["constants.F|F", "inf|finite|division by zero"], "a constant divided by zero", kind="expression")
case("expr_constant_overflow", "base_static", [("F = 5e-9       # tip force [N]", 'F = "2^1e5"')],
     ["constants.F|F", "inf|finite|overflow"], "a constant that overflows", kind="expression")
case("expr_empty", "base_static", [('length_m = "L0"', 'length_m = ""')], ["length_m", "empty"],
     "an empty expression", kind="expression")
case("expr_units", "base_static", [('length_m = "L0"', 'length_m = "1 mm"')], ["length_m", "1 mm", EXPR_BAD],
     "a unit in the value", kind="expression")
case("expr_comma", "base_static", [('radius_m = "L0/40"', 'radius_m = "2,5e-5"')], ["radius_m", "2,5e-5", EXPR_BAD],
     "a decimal comma inside an expression", kind="expression")
case("expr_trailing_operator", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-F*", 0]')],
     ["end_force_n", "-F*", EXPR_BAD], "a trailing operator", kind="expression")
case("expr_arity", "base_dynamic",
     [('force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", ', 'force_n_per_m = ["2e3*sin(pi*s, t)", ')],
     ["force_n_per_m", "sin", "argument"], "sin with two arguments", kind="expression")
case("expr_implicit_multiplication", "base_dynamic",
     [('force_n_per_m = ["2e3*sin(pi*s)*sin(8*omega0*t)", ', 'force_n_per_m = ["2e3*sin(2pi*s)", ')],
     ["force_n_per_m", "2pi", EXPR_BAD], "implicit multiplication `2pi`", kind="expression")
case("expr_unknown_variable_x", "base_newton", [('torque_nm_per_m = ["1e-7", 0, 0]', 'torque_nm_per_m = ["1e-7*x", 0, 0]')],
     ["torque_nm_per_m", "`x`|'x'|\"x\"| x ", "unknown"], "a load written in x instead of s", kind="expression")
case("expr_time_in_static", "base_newton", [('force_n_per_m = ["-2.2*Fmax", 0, 0]', 'force_n_per_m = ["-2.2*Fmax*t", 0, 0]')],
     ["force_n_per_m", "`t`|'t'|\"t\"|time", "static|dynamic|not allowed|unknown"], "a time-dependent load in a static run",
     kind="expression")
case("expr_s_in_end_load", "base_static", [('end_force_n = [0, "-F", 0]', 'end_force_n = [0, "-F*s", 0]')],
     ["end_force_n", "`s`|'s'|\"s\"|arc length", "end|not allowed|unknown"], "an end load depending on s",
     kind="expression")
case("expr_undefined_poisson", "base_static", [("shear_modulus_pa = 5.0e4", 'shear_modulus_pa = "1.1e5/(2*(1 + nu))"')],
     ["shear_modulus_pa", "nu", "unknown"], "a Poisson ratio `nu` that is not a constant", kind="expression")
case("expr_end_time_div_zero", "base_dynamic", [("end_s = 0.006", 'end_s = "0.006/0"')], ["end_s", "inf|finite"],
     "an end time divided by zero", kind="expression")
case("expr_constant_named_s", "base_static", [("F = 5e-9       # tip force [N]", "F = 5e-9\ns = 1e-3")],
     ["constants.s|`s`|'s'", "reserved|not a valid|arc length"], "a constant named s (the arc length)", kind="expression")
case("expr_constant_named_pi", "base_static", [("F = 5e-9       # tip force [N]", "F = 5e-9\npi = 3.14")],
     ["pi", "reserved|not a valid|built in|built-in"], "a constant redefining pi", kind="expression")
case("expr_constant_cycle", "base_static", [("F = 5e-9       # tip force [N]", 'F = "G/2"\nG = "2*F"')],
     ["F", "G", "circular|cycle|depend|refer"], "two constants defined by each other", kind="expression")

# --- recordings (CSV) ----------------------------------------------------------------------------
GOOD_ROWS = csv_rows(GOOD_FRAMES)
put("recordings/good.csv", csv_text(GOOD_ROWS))
put("recordings/good.npy", npy_bytes([3, NODES, 3], flat(GOOD_FRAMES)))
put("recordings/kymogram_good.npy", npy_bytes([3, 24], [a for r in kymogram_rows() for a in r]))


def recording(id, content, words, what, ext="csv", kind="recording", base="base_recording", extra_edits=None,
              fname=None):
    """A recording file `recordings/<id>.<ext>` and a case `cases/<id>.toml` reading it."""
    fname = fname or f"{id}.{ext}"
    put(f"recordings/{fname}", content)
    src = "../recordings/good.npy" if base == "base_recording_npy" else (
        "../recordings/kymogram_good.npy" if base == "base_kymogram" else "../recordings/good.csv")
    edits = [(f'file = "{src}"', f'file = "../recordings/{fname}"')] + (extra_edits or [])
    case(id, base, edits, words, what, kind=kind, name=id)
    # the recording's file name is the culprit, not the case's
    ENTRIES[-1]["words"] = [fname] + words


def rows_text(rows, **kw):
    return csv_text(rows, **kw)


def without(rows, frame, node):
    return [r for r in rows if not (r[0] == frame and r[1] == node)]


def row_word(row, line):
    return f"row {row}|line {line}"


case("rec_missing_file", "base_recording", [('file = "../recordings/good.csv"', 'file = "../recordings/missing.csv"')],
     ["missing.csv", NO_FILE], "a recording file that does not exist", kind="recording", file_word=False)
case("rec_file_is_directory", "base_recording", [('file = "../recordings/good.csv"', 'file = "../recordings"')],
     ["recordings", "directory|not a file|not a regular file"], "the recordings folder for the recording file",
     kind="recording", file_word=False)
case("kymo_missing_file", "base_kymogram",
     [('file = "../recordings/kymogram_good.npy"', 'file = "../data/elegansbot/kymogram_omega_turn.npy"')],
     ["kymogram_omega_turn.npy", NO_FILE], "a kymogram file name with _ for -", kind="recording", file_word=False)
case("rec_wrong_node_count", "base_recording", [("elements = 11", "elements = 13")],
     ["good.csv", str(NODES), str(NODES + 2), "nodes"], f"a {NODES}-node recording on a {NODES + 2}-node mesh",
     kind="recording", file_word=False)
case("rec_wrong_extension_case", "base_recording", [('file = "../recordings/good.csv"', 'file = "../recordings/good.CSV"')],
     ["good.CSV", NO_FILE + "|extension"], "an upper-case extension that is not the file's", kind="recording", file_word=False)

recording("rec_missing_row", rows_text(without(GOOD_ROWS, 1, 4)), ["frame 1", "node 4", "missing|no row"],
          "one row (frame 1, node 4) missing")
dup = GOOD_ROWS + [GOOD_ROWS[NODES + 2]]
recording("rec_duplicate_row", rows_text(dup), [f"row {len(dup)}|line {len(dup) + 1}", "frame 1", "node 2",
                                                "already|duplicate|twice"], "a row given twice")
gap = [({0: 0, 1: 2, 2: 3}[f], n, *p) for (f, n, *p) in GOOD_ROWS]
recording("rec_frame_gap", rows_text(gap), ["frame 1", "missing|no row|contiguous|gap"], "frames 0, 2, 3: frame 1 skipped")
bad = [list(r) for r in GOOD_ROWS]
bad[7][2] = "abc"
recording("rec_non_numeric", rows_text(bad), [row_word(8, 9), "x_m", "abc"], "a non-numeric cell")
bad = [list(r) for r in GOOD_ROWS]
bad[14][3] = ""
recording("rec_empty_cell", rows_text(bad), [row_word(15, 16), "y_m", "empty|missing|number"], "an empty cell")
bad = [list(r) for r in GOOD_ROWS]
bad[NODES + 3][2] = "NaN"
recording("rec_nan", rows_text(bad), ["frame 1", "node 3", "nan"], "a NaN coordinate (lost tracking)")
bad = [list(r) for r in GOOD_ROWS]
bad[2 * NODES + 1][4] = "inf"
recording("rec_inf", rows_text(bad), ["frame 2", "node 1", "inf"], "an infinite coordinate")
recording("rec_frame_u64_max", rows_text(GOOD_ROWS + [(18446744073709551615, 0, 0.0, 0.0, 0.0)]),
          ["18446744073709551615", "frame"], "a frame index of 2^64 - 1 (a -1 written as unsigned)")
recording("rec_frame_1e12", rows_text(GOOD_ROWS + [(1000000000000, 0, 0.0, 0.0, 0.0)]),
          ["1000000000000", "frame"], "a frame index of 10^12 (a timestamp in the frame column)")
recording("rec_frame_negative", rows_text(GOOD_ROWS + [(-1, 0, 0.0, 0.0, 0.0)]),
          [row_word(len(GOOD_ROWS) + 1, len(GOOD_ROWS) + 2), "frame", "-1"], "a negative frame index")
recording("rec_node_negative", rows_text([(f, -1 if n == 0 else n, *p) for (f, n, *p) in GOOD_ROWS]),
          [row_word(1, 2), "node", "-1"], "a negative node index")
recording("rec_frame_float", rows_text([(f"{f}.0", n, *p) for (f, n, *p) in GOOD_ROWS]),
          [row_word(1, 2), "frame", "0.0"], "frame indices written as floats (pandas)")
recording("rec_no_header", rows_text(GOOD_ROWS, header=None), ["header", "frame,node,x_"],
          "a recording without its header line")
recording("rec_header_no_units", rows_text(GOOD_ROWS, header="frame,node,x,y,z"), ["header", "x_m|x_um|x_U|unit"],
          "column names without their unit")
recording("rec_extra_column", rows_text([(*r, 0.04 * r[0]) for r in GOOD_ROWS], header="frame,node,x_m,y_m,z_m,t_s"),
          ["t_s", "header|column"], "an extra time column")
recording("rec_semicolons", rows_text(GOOD_ROWS, sep=";").replace("frame,node,x_m,y_m,z_m", "frame;node;x_m;y_m;z_m"),
          ["header|delimiter|separator|;", "frame;node|;"], "a semicolon-separated file (European Excel)")
short = rows_text(GOOD_ROWS).split("\n")
short[6] = ",".join(short[6].split(",")[:4])
recording("rec_short_row", "\n".join(short), [row_word(6, 7), "column|field|z_m"], "a row with 4 of its 5 cells")


def scaled(frames, f):
    return [[tuple(f * c for c in p) for p in pts] for pts in frames]


recording("rec_length_1000x", rows_text(csv_rows(scaled(GOOD_FRAMES, 1000.0))),
          ["length_m|length", "1000|1 m"], "positions in mm labelled m: the recording is 1000x the rod")
recording("rec_length_half", rows_text(csv_rows(scaled(GOOD_FRAMES, 0.5))),
          ["length_m|length", "0.5|half|5e-4|0.0005"], "a recording half the rod length")
recording("rec_length_1p2", rows_text(csv_rows(scaled(GOOD_FRAMES, 1.2))),
          ["length_m|length", "1.2|20 %|20%|0.0012|1.2e-3"], "a recording 1.2x the rod length")
three = [arc(k, n=3) for k in (400.0, 600.0, 800.0)]
recording("rec_three_nodes", rows_text(csv_rows(three)), ["3 nodes|3 points", "too few|at least|not enough"],
          "a 3-node recording (head, middle, tail) on a matching 2-element rod",
          extra_edits=[("elements = 11", "elements = 2")])
zero = [list(GOOD_FRAMES[0])] + [[(0.0, 0.0, 0.0)] * NODES] + [list(GOOD_FRAMES[2])]
recording("rec_zero_length_frame", rows_text(csv_rows(zero)), ["frame 1", "length|coincid|same point"],
          "a frame whose points all sit at the origin (tracking lost)")
glitch = [list(p) for p in GOOD_FRAMES]
glitch[2] = list(glitch[2])
glitch[2][5] = (0.5, 0.0, 0.5)
recording("rec_glitch_point", rows_text(csv_rows(glitch)), ["frame 2", "node 5"],
          "one tracking glitch half a metre away in frame 2")
recording("rec_empty_file", "", ["empty|header|no data"], "an empty recording file")
recording("rec_header_only", "frame,node,x_m,y_m,z_m\n", ["no data|no rows|empty|no frames"], "a header without rows")
ragged = [r for r in GOOD_ROWS if not (r[0] == 2 and r[1] == NODES - 1)]
recording("rec_ragged_frames", rows_text(ragged), ["frame 2", f"node {NODES - 1}|{NODES - 1} nodes", "no row|missing"],
          "the last frame one node short")
recording("rec_txt_extension", rows_text(GOOD_ROWS), [".csv|extension"],
          "a recording saved as .txt", ext="txt")

# --- NPY recordings and kymograms --------------------------------------------------------------------
GOOD_FLAT = flat(GOOD_FRAMES)


def npy_rec(id, content, words, what, base="base_recording_npy", **kw):
    recording(id, content, words, what, ext="npy", kind="npy", base=base, **kw)


npy_rec("npy_float32", npy_bytes([3, NODES, 3], GOOD_FLAT, descr="<f4", fmt="<f"), ["<f4|float32", "<f8|float64"],
        "float32 positions")
npy_rec("npy_int64", npy_bytes([3, NODES, 3], [int(v * 1e6) for v in GOOD_FLAT], descr="<i8", fmt="<q"),
        ["<i8|int64", "<f8|float64"], "integer positions (micrometres)")
npy_rec("npy_big_endian", npy_bytes([3, NODES, 3], GOOD_FLAT, descr=">f8", fmt=">d"), [">f8|big-endian", "<f8|little-endian"],
        "big-endian float64")
npy_rec("npy_2d", npy_bytes([3, NODES * 3], GOOD_FLAT), ["shape", "(3, 36)|[3, 36]", "× 3|x 3|3 axes|frames"],
        "frames × (nodes·3): the positions flattened per frame")
# (frames and nodes numbered from 1 and 2D NPY recordings are read since tracker recordings are: tests/tracker_recording.rs)
npy_rec("npy_truncated", npy_bytes([3, NODES, 3], GOOD_FLAT)[:-100], ["truncated|short|ends"], "a truncated download")
npy_rec("npy_huge_shape", npy_bytes([1000000000, 1000, 3], GOOD_FLAT), ["1000000000", "truncated|short|ends|bytes"],
        "a header claiming 10^9 frames over 720 bytes of data")
npy_rec("npy_shape_overflow", npy_bytes([2**62, 2**62, 3], GOOD_FLAT), ["shape", "overflow|too large"],
        "a header whose shape overflows")
npy_rec("npy_not_npy", rows_text(GOOD_ROWS), ["magic|not an .npy|not a numpy|npy"], "a CSV file named .npy")
npy_rec("npy_empty", b"", ["empty|magic|truncated"], "an empty .npy file")
npy_rec("npy_fortran", npy_bytes([3, NODES, 3], GOOD_FLAT, fortran=True), ["fortran"], "a Fortran-order array")
nan = list(GOOD_FLAT)
nan[3 * NODES + 3 * 2 + 1] = float("nan")
npy_rec("npy_nan", npy_bytes([3, NODES, 3], nan), ["frame 1", "node 2", "nan"], "a NaN position")
npy_rec("npy_zero_frames", npy_bytes([0, NODES, 3], []), ["0 frames|no frames|empty|at least 1 frame"],
        "an array of zero frames")
npy_rec("npy_wrong_nodes", npy_bytes([3, 10, 3], flat([arc(k, n=10) for k in (400.0, 600.0, 800.0)])),
        ["10", str(NODES)], f"10 nodes per frame on a {NODES}-node mesh")
npy_rec("npy_length_1000x", npy_bytes([3, NODES, 3], flat(scaled(GOOD_FRAMES, 1000.0))), ["length_m|length", "1000|1 m"],
        "positions in mm labelled m")
npy_rec("npy_trailing_bytes", npy_bytes([3, NODES, 3], GOOD_FLAT) + b"\0" * 8, ["bytes after|trailing|extra"],
        "8 stray bytes after the data")
npy_rec("npy_version_9", npy_bytes([3, NODES, 3], GOOD_FLAT)[:6] + bytes([9]) + npy_bytes([3, NODES, 3], GOOD_FLAT)[7:],
        ["version"], "an unknown NPY format version")
npy_rec("kymo_3d", npy_bytes([3, NODES, 3], GOOD_FLAT), ["2 axes|frames × joint|joint angles", "(3, 12, 3)|[3, 12, 3]"],
        "a position recording given as a kymogram", base="base_kymogram")
kn = [a for r in kymogram_rows() for a in r]
kn[24 + 7] = float("nan")
npy_rec("kymo_nan", npy_bytes([3, 24], kn), ["frame 1", "joint 7", "nan"], "a NaN joint angle", base="base_kymogram")
npy_rec("kymo_degrees", npy_bytes([3, 24], [math.degrees(a) for r in kymogram_rows() for a in r]),
        ["joint", "rad|radian|degree"], "joint angles in degrees (max 17.2°) for radians", base="base_kymogram")
npy_rec("kymo_float32", npy_bytes([3, 24], [a for r in kymogram_rows() for a in r], descr="<f4", fmt="<f"),
        ["<f4|float32", "<f8|float64"], "a float32 kymogram", base="base_kymogram")

# --- sweeps -------------------------------------------------------------------------------------------
def sweep(id, sets, words, what, base="base_static"):
    args = ["sweep", "{cat}/cases/" + base + ".toml"]
    for s in sets:
        args += ["--set", s]
    args += ["--out", "{out}", "--quiet", "--jobs", "1"]
    entry(id, "cli", args, words, what)


sweep("sweep_unknown_key", ["young=1e5,2e5"], ["young", UNKNOWN], "a key that cannot be swept")
sweep("sweep_bad_value", ["elements=ten"], ["elements", "ten", "number"], "a value that is not a number")
sweep("sweep_duplicate_value", ["elements=10,10"], ["elements", "10", "twice|duplicate|repeated"],
      "the same value twice (two runs into one folder)")
sweep("sweep_key_twice", ["elements=10", "elements=20"], ["elements", "twice|duplicate|repeated"],
      "the same key in two --set options")
sweep("sweep_tolerance_zero", ["tolerance=0,1e-9"], ["tolerance", "0", "> 0|positive|(0, 1)"], "a swept tolerance of 0")
sweep("sweep_elements_zero", ["elements=0,20"], ["elements", "0", "at least|≥|>=|positive"], "a swept element count 0")
sweep("sweep_elements_fraction", ["elements=2.5"], ["elements", "2.5", "integer"], "a fractional element count")
sweep("sweep_empty_values", ["relaxation="], ["relaxation", "value|key=value"], "a key without values")
sweep("sweep_other_analysis_key", ["lambda_d=1e-6,1e-4"], ["lambda_d", "static|unknown|not"],
      "an inverse weight swept on a static case")
sweep("sweep_steps_on_static", ["steps=10,20"], ["steps", "static|unknown|not"], "time steps swept on a static case")
sweep("sweep_no_equals", ["elements:10,20"], ["elements:10,20", "key=value|="], "`:` for `=`")
sweep("sweep_nan", ["relaxation=nan"], ["relaxation", "nan", "number|finite"], "a NaN value")
sweep("sweep_elements_huge", ["elements=20,10000000"], ["elements", "10000000", MEMORY], "10 million elements in a sweep")
sweep("sweep_semicolons", ["tolerance=1e-9;1e-8"], ["tolerance", "1e-9;1e-8"], "semicolons between values")
sweep("sweep_relaxation_newton", ["relaxation=0.3,0.5"], ["relaxation", "newton"], "a relaxation swept on a Newton case",
      base="base_newton")

# --- audit specs ----------------------------------------------------------------------------------------
GOOD_SPEC = '''title = "catalogue: a small audit spec"
section = "§5.2"
paper_figures = "Fig. 7"

[runs.t5]
case = "../cases/base_static.toml"

[runs.mesh]
case = "../cases/base_static.toml"
grid = { elements = [20, 40] }

[[claims]]
id = "t5-small"
where = "§5.2"
statement = "the tip deflection is small"
paper = "5 %"
check = { kind = "below", run = "t5", metric = "eq63_curve_rel_error", limit = 0.02 }
expect = "reproduced"

[[claims]]
id = "mesh"
where = "§5.2"
statement = "converged"
paper = "converged"
check = { kind = "within_factor", run = "mesh", metric = "tip_y_m", factor = 1.01 }
expect = "reproduced"

[[figures]]
file = "deflection.svg"
title = "deflection"
show = { kind = "deflection", runs = ["t5"] }
'''
put("specs/good.toml", GOOD_SPEC)


def spec(id, edits, words, what):
    text = GOOD_SPEC
    for old, new in edits:
        text = edit(text, old, new)
    put(f"specs/{id}.toml", text)
    entry(id, "audit", ["audit", "{cat}/specs/" + id + ".toml", "--quick", "--out", "{out}", "--quiet", "--jobs", "1"],
          [f"{id}.toml"] + words, what)


spec("audit_unknown_key", [('section = "§5.2"', 'section = "§5.2"\nauthor = "me"')], ["author", UNKNOWN],
     "a key audit specs do not have")
spec("audit_missing_case", [('case = "../cases/base_static.toml"\n\n[runs.mesh]', 'case = "../cases/nope.toml"\n\n[runs.mesh]')],
     ["nope.toml", NO_FILE], "a run whose case file does not exist")
spec("audit_grid_unknown_key", [("grid = { elements = [20, 40] }", "grid = { lambda_q = [1, 2] }")],
     ["lambda_q", UNKNOWN], "a grid key that does not exist")
spec("audit_claim_unknown_run", [('run = "t5", metric', 'run = "t50", metric')], ["t50", "run"],
     "a claim reading a run that does not exist")
spec("audit_duplicate_claim", [('id = "mesh"', 'id = "t5-small"')], ["t5-small", "twice|duplicate"],
     "two claims with one id")
spec("audit_bad_check_kind", [('kind = "below"', 'kind = "smaller"')], ["smaller", "check|kind|variant"],
     "a check kind that does not exist")
spec("audit_figure_not_svg", [('file = "deflection.svg"', 'file = "deflection.png"')], ["deflection.png", "svg"],
     "a figure that is not SVG")
spec("audit_syntax", [('title = "deflection"', 'title = "deflection')], ["line"], "an unclosed string")
spec("audit_empty_grid", [("grid = { elements = [20, 40] }", "grid = { elements = [] }")], ["elements", "empty|values"],
     "a grid without values")
spec("audit_set_unknown_key", [('case = "../cases/base_static.toml"\n\n[runs.mesh]',
                                'case = "../cases/base_static.toml"\nset = { "solver.max_iter" = 5 }\n\n[runs.mesh]')],
     ["max_iter", UNKNOWN], "a `set` override of a key case files do not have")
spec("audit_bad_verdict", [('expect = "reproduced"\n\n[[claims]]', 'expect = "confirmed"\n\n[[claims]]')],
     ["confirmed", "expect|verdict|variant"], "a verdict that does not exist")
spec("audit_unknown_metric", [('metric = "eq63_curve_rel_error"', 'metric = "eq63_error"')],
     ["eq63_error", "metric", "unknown|no such|not"], "a claim on a metric no run writes")
entry("audit_foreign_out", "folder",
      ["audit", "{cat}/specs/good.toml", "--quick", "--out", "{tmp}/notes", "--quiet", "--jobs", "1"],
      ["notes", "audit"], "--out pointing at a folder of the user's own files",
      files={"notes/notes.txt": "my notes\n"})
put("folders/no_specs/README.txt", "no specs here\n")
entry("audit_no_specs", "folder", ["audit", "{cat}/folders/no_specs", "--quick", "--out", "{out}", "--quiet"],
      ["no_specs", "spec|toml"], "a folder without audit specs")

# --- resources ---------------------------------------------------------------------------------------
entry("run_dev_zero", "resource", ["run", "/dev/zero", "--out", "{out}", "--quiet"],
      ["/dev/zero", "regular file|not a file|too large|size"], "a device that never ends given as the case")
entry("run_dev_urandom", "resource", ["run", "/dev/urandom", "--out", "{out}", "--quiet"],
      ["/dev/urandom", "regular file|not a file|too large|size"], "a random-bytes device given as the case")
entry("modes_no_density", "resource", ["modes", "{cat}/cases/base_static.toml"], ["base_static.toml", "density_kg_m3", MISSING],
      "`modes` on a case without density (must not assume 1 kg/m³)")
case("modes_huge", "base_dynamic", [("elements = 10", "elements = 100000")], ["100000|elements", MEMORY],
     "`modes` with 1e5 elements: a dense eigenproblem of 600 000 unknowns (2.9 TB)", kind="resource", cmd="modes")
entry("modes_count_zero", "cli", ["modes", "{cat}/cases/base_dynamic.toml", "--count", "0"],
      ["count", "0", "at least|≥|>=|positive"], "`modes --count 0`")

# --- folders and output locations -------------------------------------------------------------------------
put("folders/list_invalid/good.toml", BASE_STATIC)
put("folders/list_invalid/bad.toml", edit(BASE_STATIC, "young_modulus_pa = 1.1e5", "young_modulus_pa = -1.1e5"))
entry("list_invalid_case", "folder", ["list", "{cat}/folders/list_invalid"],
      ["bad.toml", "young_modulus_pa", POS], "`list` on a folder holding an invalid case")
put("folders/list_syntax/good.toml", BASE_STATIC)
put("folders/list_syntax/broken.toml", edit(BASE_STATIC, 'shape = "circle"', 'shape = "circle'))
entry("list_syntax_error", "folder", ["list", "{cat}/folders/list_syntax"], ["broken.toml", "line"],
      "`list` on a folder holding a case with a TOML syntax error")
entry("list_empty_folder", "folder", ["list", "{cat}/folders/no_specs"], ["no_specs", "toml|case"],
      "`list` on a folder without cases")
entry("list_missing_folder", "folder", ["list", "{cat}/folders/nope"], ["nope", NO_FILE], "`list` on a missing folder")
entry("list_on_file", "folder", ["list", "{cat}/cases/base_static.toml"], ["base_static.toml", "directory|folder"],
      "`list` given a case file instead of a folder")
entry("run_directory", "folder", ["run", "{cat}/cases", "--out", "{out}", "--quiet"], ["cases", "directory|folder"],
      "a folder given as the case")
entry("run_missing_case", "folder", ["run", "{cat}/cases/timoshenko.toml", "--out", "{out}", "--quiet"],
      ["timoshenko.toml", NO_FILE], "a case file that does not exist")
entry("out_is_file", "folder", ["run", "{cat}/cases/base_static.toml", "--out", "{tmp}/results.txt", "--quiet"],
      ["results.txt", "not a directory|is a file|regular file|exists"], "--out pointing at an existing regular file",
      files={"results.txt": "keep me\n"})
entry("out_below_file", "folder", ["run", "{cat}/cases/base_static.toml", "--out", "{tmp}/results.txt/run1", "--quiet"],
      ["results.txt", "not a directory|is a file|regular file"], "--out below an existing regular file",
      files={"results.txt": "keep me\n"})
entry("out_empty", "folder", ["run", "{cat}/cases/base_static.toml", "--out", "", "--quiet"],
      ["--out", "empty|value is required|no value|none was supplied"], "an empty --out (an unset shell variable): results would land in the working folder")
entry("out_is_file_clip", "folder", ["run", "{cat}/cases/base_recording.toml", "--out", "{tmp}/results.txt", "--quiet"],
      ["results.txt", "not a directory|is a file|regular file|exists"], "--out at a regular file on a clip run",
      files={"results.txt": "keep me\n"})
entry("out_is_file_sweep", "folder",
      ["sweep", "{cat}/cases/base_static.toml", "--set", "elements=10,20", "--out", "{tmp}/results.txt", "--quiet"],
      ["results.txt", "not a directory|is a file|regular file|exists"], "--out at a regular file on a sweep",
      files={"results.txt": "keep me\n"})

# --- command line -------------------------------------------------------------------------------------------
entry("cli_bad_engine", "cli", ["run", "{cat}/cases/base_static.toml", "--engine", "abaqus", "--out", "{out}"],
      ["abaqus", "rust", "freefem"], "an engine that does not exist")
entry("cli_no_case", "cli", ["run", "--out", "{out}"], ["case", "required"], "`run` without a case")
entry("cli_unknown_subcommand", "cli", ["solve", "{cat}/cases/base_static.toml"], ["solve", "unrecognized|unknown"],
      "a subcommand that does not exist")
entry("cli_two_cases", "cli", ["run", "{cat}/cases/base_static.toml", "{cat}/cases/base_newton.toml", "--out", "{out}"],
      ["base_newton.toml", "unexpected|one case"], "two cases to one `run`")
entry("cli_frames_zero", "cli", ["compare", "{cat}/cases/base_recording.toml", "--frames", "0", "--out", "{out}"],
      ["--frames", "0"], "`compare --frames 0`")
entry("cli_freefem_clip", "cli", ["run", "{cat}/cases/base_recording.toml", "--engine", "freefem", "--out", "{out}"],
      ["freefem", "clip"], "`run --engine freefem` on a clip")
entry("cli_sweep_without_set", "cli", ["sweep", "{cat}/cases/base_static.toml", "--out", "{out}"], ["--set", "required"],
      "`sweep` without --set")
entry("cli_count_negative", "cli", ["modes", "{cat}/cases/base_dynamic.toml", "--count", "-1"], ["-1", "count"],
      "`modes --count -1`")
entry("cli_stdin_syntax", "cli", ["run", "/dev/stdin", "--out", "{out}", "--quiet"], ["/dev/stdin|stdin", "line 3"],
      "a case with a syntax error piped to `run /dev/stdin`", stdin='description = "piped"\n[rod]\nlength_m = 1e-3 m\n')
entry("cli_stdin_empty", "cli", ["run", "/dev/stdin", "--out", "{out}", "--quiet"], ["/dev/stdin", "empty"],
      "`run /dev/stdin` with nothing piped", stdin="")
entry("cli_compare_frames_no_clip", "cli", ["compare", "{cat}/cases/base_static.toml", "--frames", "5", "--out", "{out}"],
      ["--frames", "clip"], "`compare --frames` on a case without a clip")


# ---------------------------------------------------------------------------------------------
# Write everything.

def toml_str(s):
    out = '"'
    for ch in s:
        if ch == '"':
            out += '\\"'
        elif ch == "\\":
            out += "\\\\"
        elif ch == "\n":
            out += "\\n"
        elif ord(ch) < 0x20:
            out += "\\u%04x" % ord(ch)
        else:
            out += ch
    return out + '"'


def toml_list(items):
    return "[" + ", ".join(toml_str(i) for i in items) + "]"


def main():
    for sub in ("cases", "recordings", "specs", "folders"):
        shutil.rmtree(os.path.join(HERE, sub), ignore_errors=True)
    for path, content in FILES.items():
        full = os.path.join(HERE, path)
        os.makedirs(os.path.dirname(full), exist_ok=True)
        with open(full, "wb") as f:
            f.write(content.encode() if isinstance(content, str) else content)
    lines = [
        "# The catalogue of bad inputs (issue 15), written by generate.py: every entry is one mistake a",
        "# new user could make; tests/catalogue.rs runs each through the real binary and asserts a",
        "# non-zero exit without a signal or panic, an error naming every word (case-insensitive; \"a|b\"",
        "# is either), and no output that could be taken for a result. {cat} is this folder, {out} a",
        "# fresh output folder, {tmp} the run's working folder (where `files` are created first).",
        "",
        "# The valid cases every entry changes in one place (run by the test as a control).",
        "bases = " + toml_list(sorted(BASES)),
    ]
    for e in ENTRIES:
        lines += ["", "[[entry]]", f"id = {toml_str(e['id'])}", f"kind = {toml_str(e['kind'])}",
                  f"what = {toml_str(e['what'])}", f"args = {toml_list(e['args'])}", f"words = {toml_list(e['words'])}"]
        if e["stdin"] is not None:
            lines.append(f"stdin = {toml_str(e['stdin'])}")
        if e["files"]:
            lines.append("files = { " + ", ".join(f"{toml_str(k)} = {toml_str(v)}" for k, v in e["files"].items()) + " }")
    with open(os.path.join(HERE, "catalogue.toml"), "w") as f:
        f.write("\n".join(lines) + "\n")
    kinds = {}
    for e in ENTRIES:
        kinds[e["kind"]] = kinds.get(e["kind"], 0) + 1
    print(f"{len(ENTRIES)} entries: " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))


main()
