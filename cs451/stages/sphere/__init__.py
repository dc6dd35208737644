"""Stage 1, the lit sphere: its interface, and the scaffolding that draws with a student's functions.

The scaffolding holds no solution. It carries over two ideas of the original
GLUT program: the display list becomes GPU buffers built once (``SphereRenderer``),
and the fixed-function state becomes uniforms declared in ``GLSL_INTERFACE``.
Everything a student writes (matrices, mesh, shaders, reshape, keys) is called
through :data:`STAGE`, or replaced by trusted inputs ``given`` by the autograder.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ... import schema
from ...errors import KitError
from ...gl import compile_program, create_context
from .tolerances import SAME_QUERY
from ...scene import Camera, DirectionalLight, Group, PointLight, Scene, Sphere, parse_scene, walk_objects
from ...schema import Context, field
from ..base import Out, Probes, Stage, Task, functions_replaced, part

MAX_LIGHTS = 8

#: Put in front of every student shader: the version line, and the uniforms and inputs the kit sets.
GLSL_INTERFACE = f"""#version 330
#define MAX_LIGHTS {MAX_LIGHTS}
uniform mat4 u_model_view;      // object to eye space
uniform mat4 u_projection;      // eye to clip space
uniform mat3 u_normal_matrix;   // inverse transpose of u_model_view's upper 3x3
uniform int u_num_lights;
uniform vec4 u_light_position[MAX_LIGHTS];    // eye space; w = 0 for a directional light (towards the light)
uniform vec3 u_light_ambient[MAX_LIGHTS];
uniform vec3 u_light_diffuse[MAX_LIGHTS];
uniform vec3 u_light_specular[MAX_LIGHTS];
uniform vec3 u_light_attenuation[MAX_LIGHTS]; // constant, linear, quadratic
uniform vec3 u_global_ambient;
uniform vec3 u_mat_ambient;
uniform vec3 u_mat_diffuse;
uniform vec3 u_mat_specular;
uniform vec3 u_mat_emission;
uniform float u_mat_shininess;
uniform bool u_local_viewer;
"""
VERTEX_INPUTS = "in vec3 in_position;  // object space\nin vec3 in_normal;\n"
FRAGMENT_OUTPUT = "out vec4 frag_color;\n"

SHADERS = (Out("vertex_source", kind="text"), Out("fragment_source", kind="text"))
TASKS = (
    Task("S1", "perspective", "Perspective projection", ("fovy", "aspect", "near", "far"), (Out("matrix", (4, 4)),)),
    Task("S2", "look_at", "The look-at view matrix", ("eye", "center", "up"), (Out("matrix", (4, 4)),)),
    Task("S3", "model_view_matrices", "The modelview matrix", ("view", "calls"), (Out("matrices", (None, 4, 4)),)),
    Task("S4", "sphere_mesh", "The sphere mesh", ("radius", "slices", "stacks"),
         (Out("positions", (None, 3)), Out("normals", ("len(positions)", 3)),
          Out("triangles", (None, 3), "i", below="len(positions)"))),
    Task("S5", "gouraud_shaders", "Gouraud shading", (), SHADERS),
    Task("S6", "phong_shaders", "Phong shading", (), SHADERS),
    Task("S7", "reshape", "Resizing the window", ("width", "height", "camera"),
         (Out("viewport", (4,), "i"), Out("projection", (4, 4)))),
    Task("S8", "handle_key", "Keyboard controls", ("key", "state"), (Out("state", kind="any"),)),
    Task("S9", "stereo_projection", "A stereo pair",
         ("fovy", "aspect", "near", "far", "separation", "convergence", "eye"), (Out("matrix", (4, 4)),), optional=True),
)


@dataclass(frozen=True)
class ViewState:
    """What the keyboard changes in the viewer (S8)."""
    running: bool = True
    shading: Literal["gouraud", "phong"] = "gouraud"
    slices: int = 32
    stacks: int = 32


@dataclass(frozen=True)
class SphereOptions:
    shading: Literal["gouraud", "phong"] = field("Gouraud (per-vertex lighting, as the original) or Phong (per-fragment).", "gouraud")
    local_viewer: bool = field("GL_LIGHT_MODEL_LOCAL_VIEWER: the specular half-vector uses the direction to the eye.", True)


def spheres(scene: Scene) -> list[Sphere]:
    """The scene's spheres in drawing order, groups walked depth first."""
    found = []
    for obj, where in walk_objects(scene.objects):
        if not isinstance(obj, Sphere):
            raise KitError(f"{scene.label}: {where.path}: stage 1 draws spheres, not a {type(obj).__name__}")
        found.append(obj)
    if not found:
        raise KitError(f"{scene.label}: objects: stage 1 draws spheres, and this scene has none")
    return found


def drawing_calls(scene: Scene) -> list[tuple]:
    """The modelview calls that place the scene's spheres, in the order an OpenGL 1.x program would make them.

    A group is ``push``, its transforms in order, its objects, ``pop``; a sphere off the origin is ``push``,
    ``translate`` to its centre, ``draw``, ``pop``; a sphere at the origin is just ``draw``. One ``draw`` per
    sphere of :func:`spheres`, in the same order: what S3 runs.
    """
    spheres(scene)  # refuses, by its path, anything in a group that is not a sphere
    calls: list[tuple] = []

    def place(objects: list) -> None:
        for obj in objects:
            if isinstance(obj, Group):
                calls.append(("push",))
                calls.extend(t.call for t in obj.transform)
                place(obj.objects)
                calls.append(("pop",))
            elif any(obj.center):
                calls.extend([("push",), ("translate", *map(float, obj.center)), ("draw",), ("pop",)])
            else:
                calls.append(("draw",))
    place(scene.objects)
    return calls


# --- calling the student's functions, with checks on what they return --------

def _perspective(impl: Any, fovy: float, aspect: float, near: float, far: float) -> np.ndarray:
    return STAGE.call(impl, "S1", fovy, aspect, near, far)


def _look_at(impl: Any, eye: Any, center: Any, up: Any) -> np.ndarray:
    return STAGE.call(impl, "S2", np.array(eye, float), np.array(center, float), np.array(up, float))


def _model_views(impl: Any, view: np.ndarray, calls: list[tuple]) -> np.ndarray:
    matrices = STAGE.call(impl, "S3", np.array(view, float), [tuple(c) for c in calls])
    draws = sum(1 for c in calls if c[0] == "draw")
    if len(matrices) != draws:
        raise KitError(f"S3 model_view_matrices() returned {len(matrices)} matrices for {draws} draw calls")
    return matrices


def _mesh(impl: Any, radius: float, slices: int, stacks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return STAGE.call(impl, "S4", radius, slices, stacks)


def _shaders(impl: Any, shading: str) -> tuple[str, str]:
    return STAGE.call(impl, "S5" if shading == "gouraud" else "S6")


def _reshape(impl: Any, width: int, height: int, camera: Camera) -> tuple[tuple[int, int, int, int], np.ndarray]:
    viewport, projection = STAGE.call(impl, "S7", width, height, camera)
    return tuple(int(v) for v in viewport), projection  # type: ignore[return-value]


def _key(impl: Any, key: str, state: ViewState) -> ViewState:
    out = STAGE.call(impl, "S8", key, state)
    if not isinstance(out, ViewState):
        raise KitError(f"S8 handle_key() must return a ViewState, got {type(out).__name__}")
    return out


# --- drawing ----------------------------------------------------------------

def _light_uniforms(scene: Scene, view: np.ndarray) -> dict[str, np.ndarray]:
    lights = list(scene.lights)
    for k, light in enumerate(lights):
        if not isinstance(light, (PointLight, DirectionalLight)):
            raise KitError(f"{scene.label}: lights[{k}]: stage 1 lights with point and directional lights (OpenGL "
                           f"1.x's), not a {type(light).__name__}")
    if len(lights) > MAX_LIGHTS:
        raise KitError(f"{scene.label}: lights: stage 1 supports at most {MAX_LIGHTS} lights (OpenGL 1.x's GL_LIGHT0..7)")
    pos = np.zeros((MAX_LIGHTS, 4))
    amb, dif, spe = (np.zeros((MAX_LIGHTS, 3)) for _ in range(3))
    att = np.tile([1.0, 0.0, 0.0], (MAX_LIGHTS, 1))
    for i, light in enumerate(lights):
        if isinstance(light, PointLight):
            p = np.array([*light.position, 1.0])
            att[i] = light.attenuation
        else:
            p = np.array([*(-np.asarray(light.direction)), 0.0])  # GL stores the direction towards the light
        pos[i] = p if light.space == "eye" else view @ p
        amb[i], dif[i], spe[i] = light.ambient, light.diffuse, light.specular
    return {"u_num_lights": np.array(len(lights)), "u_light_position": pos, "u_light_ambient": amb,
            "u_light_diffuse": dif, "u_light_specular": spe, "u_light_attenuation": att}


class SphereRenderer:
    """Buffers built once, drawn every frame: the display list of the original program, in modern OpenGL."""

    def __init__(self, ctx: Any, shaders: tuple[str, str], meshes: list[tuple[np.ndarray, np.ndarray, np.ndarray]],
                 task: str = "S5"):
        self.ctx = ctx
        vs, fs = shaders
        self.program = compile_program(ctx, task, (GLSL_INTERFACE + VERTEX_INPUTS, vs, ""),
                                       (GLSL_INTERFACE + FRAGMENT_OUTPUT, fs, ""))
        self.vaos = []
        for positions, normals, triangles in meshes:
            vbo = ctx.buffer(np.hstack([positions, normals]).astype("f4").tobytes())
            ibo = ctx.buffer(triangles.astype("i4").tobytes())
            attributes = [name for name in ("in_position", "in_normal") if name in self.program]
            layout = " ".join("3f" if n in attributes else "3x4" for n in ("in_position", "in_normal"))
            self.vaos.append(ctx.vertex_array(self.program, [(vbo, layout, *attributes)], ibo))

    def _set(self, name: str, value: Any) -> None:
        if name in self.program:  # the GLSL compiler drops uniforms a shader does not use
            self.program[name].write(np.asarray(value, dtype="i4" if name == "u_num_lights" else "f4").tobytes())

    def draw(self, scene: Scene, view: np.ndarray, model_views: np.ndarray, projection: np.ndarray,
             local_viewer: bool) -> None:
        """One frame: lights placed by ``view`` (as glLightfv after gluLookAt), sphere k by ``model_views[k]``."""
        ctx = self.ctx
        ctx.enable(ctx.DEPTH_TEST)
        ctx.clear(*scene.image.background, 1.0, depth=1.0)
        for name, value in _light_uniforms(scene, view).items():
            self._set(name, value)
        self._set("u_projection", projection.T)
        self._set("u_global_ambient", scene.ambient)
        if "u_local_viewer" in self.program:
            self.program["u_local_viewer"].value = bool(local_viewer)
        for vao, sphere, model_view in zip(self.vaos, spheres(scene), model_views):
            m = scene.material(sphere.material)
            self._set("u_model_view", model_view.T)
            self._set("u_normal_matrix", np.linalg.inv(model_view[:3, :3]))  # (M^-1)^T, transposed for GL
            self._set("u_mat_ambient", m.ambient)
            self._set("u_mat_diffuse", m.diffuse)
            self._set("u_mat_specular", m.specular)
            self._set("u_mat_emission", m.emission)
            self._set("u_mat_shininess", m.shininess)
            vao.render()


def _read_pixels(fbo: Any, width: int, height: int) -> np.ndarray:
    data = np.frombuffer(fbo.read(components=3, alignment=1), dtype=np.uint8).reshape(height, width, 3)
    return np.flipud(data).astype(np.float64) / 255.0


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, shading: str | None = None,
           given: dict[str, Any] | None = None, ctx: Any = None) -> np.ndarray:
    """Render a stage-1 scene with a student's functions; ``given`` replaces some of them with trusted values.

    ``given`` may hold ``viewport``, ``projection``, ``view``, ``model_views`` and ``mesh0``, ``mesh1``… (one per
    sphere).
    Returns a linear float image (h, w, 3) in [0, 1], 8 bits deep as the original window.
    """
    given = given or {}
    opts = STAGE.options(scene)
    shading = shading or opts.shading
    width, height = size or (scene.image.width, scene.image.height)
    cam = scene.camera
    if "projection" in given:
        viewport, projection = given["viewport"], given["projection"]
    else:
        viewport, projection = _reshape(impl, width, height, cam)
    view = given["view"] if "view" in given else _look_at(impl, cam.eye, cam.center, cam.up)
    model_views = given["model_views"] if "model_views" in given else _model_views(impl, view, drawing_calls(scene))
    meshes = [given.get(f"mesh{i}") or _mesh(impl, s.radius, s.slices, s.stacks) for i, s in enumerate(spheres(scene))]
    shaders = _shaders(impl, shading)
    ctx = ctx or create_context()
    fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((width, height), 4)],
                          depth_attachment=ctx.depth_renderbuffer((width, height)))
    fbo.use()
    ctx.viewport = tuple(int(v) for v in viewport)
    renderer = SphereRenderer(ctx, shaders, meshes, task="S5" if shading == "gouraud" else "S6")
    renderer.draw(scene, view, model_views, projection, opts.local_viewer)
    ctx.finish()
    return _read_pixels(fbo, width, height)


# --- probes: what the autograder's worker asks a submission for ------------------

PROBES = Probes()


@PROBES.register
def probe_perspective(impl: Any, fovy: float, aspect: float, near: float, far: float) -> dict[str, np.ndarray]:
    """S1 alone: the projection matrix ``(4, 4)`` for the given frustum, compared with the truth's."""
    return {"matrix": _perspective(impl, fovy, aspect, near, far)}


@PROBES.register
def probe_stereo_projection(impl: Any, fovy: float, aspect: float, near: float, far: float, separation: float,
                            convergence: float) -> dict[str, np.ndarray]:
    """S9 for both eyes: the left eye's matrix, then the right's."""
    return {"matrices": np.stack([STAGE.call(impl, "S9", fovy, aspect, near, far, separation, convergence, eye)
                                  for eye in (-1, 1)])}


@PROBES.register
def probe_look_at(impl: Any, eye: list, center: list, up: list) -> dict[str, np.ndarray]:
    """S2 alone: the view matrix ``(4, 4)`` for the given eye, centre and up, compared with the truth's."""
    return {"matrix": _look_at(impl, eye, center, up)}


@PROBES.register
def probe_model_view_matrices(impl: Any, view: list, calls: list) -> dict[str, np.ndarray]:
    """S3 alone on a given view and list of modelview calls: a matrix per ``draw`` ``(k, 4, 4)``, compared
    with the truth's."""
    return {"matrices": _model_views(impl, np.array(view, float), calls)}


@PROBES.register
def probe_sphere_mesh(impl: Any, radius: float, slices: int, stacks: int) -> dict[str, np.ndarray]:
    """S4 alone: the mesh's positions ``(n, 3)``, normals ``(n, 3)`` and triangles ``(t, 3) int``, for the mesh
    checks against freeglut's sphere."""
    positions, normals, triangles = _mesh(impl, radius, slices, stacks)
    return {"positions": positions, "normals": normals, "triangles": triangles}


PERSPECTIVE_ARGS = ("fovy", "aspect", "near", "far")


@PROBES.register
def probe_reshape(impl: Any, width: int, height: int, camera: dict, perspective_query: np.ndarray | None = None,
                  perspective_answer: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The submission's S7. Given the reference's S1 answer (:func:`probe_reshape_parts`), a call of the
    submission's S1 with the same arguments gets that answer, so that an S1 bug costs S1's points only."""
    cam = schema.parse_record(Camera, camera, Context("<probe>", "camera"))
    if perspective_query is None or perspective_answer is None:
        viewport, projection = _reshape(impl, width, height, cam)
    else:
        def wrap(own: Any) -> Any:
            def answered(*args: Any, **kwargs: Any) -> Any:
                values = list(args) + [kwargs[k] for k in PERSPECTIVE_ARGS[len(args):] if k in kwargs]
                try:
                    same = len(values) == 4 and np.allclose(np.asarray(values, float), perspective_query, rtol=SAME_QUERY, atol=0)
                except (TypeError, ValueError):
                    same = False
                return np.array(perspective_answer) if same else own(*args, **kwargs)
            return answered
        with functions_replaced(STAGE, impl, {"S1": wrap}):
            viewport, projection = _reshape(impl, width, height, cam)
    return {"viewport": np.array(viewport), "projection": projection}


@PROBES.register
def probe_reshape_parts(impl: Any, width: int, height: int, camera: dict) -> dict[str, np.ndarray]:
    """Trusted input of a reshape test (run on the reference only): the call its S7 makes to S1, and the answer."""
    calls: list = []

    def wrap(own: Any) -> Any:
        def recording(*args: Any) -> Any:
            calls.append((args, own(*args)))
            return calls[-1][1]
        return recording
    with functions_replaced(STAGE, impl, {"S1": wrap}):
        probe_reshape(impl, width, height, camera)
    args, answer = calls[0]
    return {"perspective_query": np.asarray(args, dtype=np.float64), "perspective_answer": np.asarray(answer)}


@PROBES.register
def probe_handle_key(impl: Any, presses: list[tuple[str, dict]]) -> dict[str, np.ndarray]:
    """The state after each (key, state) press, as parallel arrays."""
    states = [_key(impl, key, ViewState(**state)) for key, state in presses]
    return {"running": np.array([s.running for s in states]), "shading": np.array([s.shading for s in states]),
            "slices": np.array([s.slices for s in states]), "stacks": np.array([s.stacks for s in states])}


@PROBES.register
def probe_parts(impl: Any, scene: dict, size: list[int], shading: str | None = None) -> dict[str, np.ndarray]:
    """Everything but the shaders: what the autograder feeds as trusted inputs to a shader test.

    Takes the render probe's parameters; ``shading`` does not change the parts.
    """
    sc = parse_scene(scene, "<probe scene>")
    viewport, projection = _reshape(impl, size[0], size[1], sc.camera)
    cam = sc.camera
    view = _look_at(impl, cam.eye, cam.center, cam.up)
    out = {"viewport": np.array(viewport), "projection": projection, "view": view,
           "model_views": _model_views(impl, view, drawing_calls(sc))}
    for i, s in enumerate(spheres(sc)):
        for key, arr in zip(("positions", "normals", "triangles"), _mesh(impl, s.radius, s.slices, s.stacks)):
            out[f"mesh{i}_{key}"] = arr
    return out


@PROBES.register
def probe_render(impl: Any, scene: dict, size: list[int], shading: str | None = None,
                 **given_arrays: np.ndarray) -> dict[str, np.ndarray]:
    """Render ``scene``; the trusted parts arrive as arrays named as :func:`probe_parts` returns them."""
    given: dict[str, Any] = {}
    if "projection" in given_arrays:
        given["projection"] = given_arrays["projection"]
        given["viewport"] = tuple(int(v) for v in given_arrays["viewport"])
    for name in ("view", "model_views"):
        if name in given_arrays:
            given[name] = given_arrays[name]
    i = 0
    while f"mesh{i}_positions" in given_arrays:
        given[f"mesh{i}"] = tuple(given_arrays[f"mesh{i}_{k}"] for k in ("positions", "normals", "triangles"))
        i += 1
    sc = parse_scene(scene, "<probe scene>")
    return {"image": render(sc, impl, tuple(size), shading=shading, given=given)}  # type: ignore[arg-type]


def run_demo(module: Any, output: Path, window: bool, frames: int | None) -> list[Path]:
    """The notes' window, or its images without a display (:mod:`cs451.stages.sphere.demo`)."""
    run = part(__name__, "demo").demo
    return run(module, output, window, frames)


#: bytes per slice × stack cell of a sphere's mesh, measured on the reference (184 at 2000 × 2000) with margin
MESH_CELL_BYTES = 256


def estimate(scene: Scene, size: tuple[int, int] | None = None) -> list:
    """The memory a render needs, from the scene alone: the image, and the spheres' meshes, blamed on the sphere that
    holds most of their cells where one does (else on ``objects``)."""
    from ...limits import Cost
    w, h = size or (scene.image.width, scene.image.height)
    costs = [Cost("image.width", 64.0 * w * h, f"a {w}x{h} image")]
    spheres = [(obj, where) for obj, where in walk_objects(scene.objects) if isinstance(obj, Sphere)]
    if len(spheres) == 1:   # one sphere: its tessellation is the field to blame
        (obj, where), = spheres
        costs.append(Cost(f"{where.path}.slices", MESH_CELL_BYTES * obj.slices * obj.stacks,
                          f"a mesh of {obj.slices} × {obj.stacks} cells"))
    elif spheres:           # many: their number is, unless one of them alone asks for most of it
        cells = [obj.slices * obj.stacks for obj, _ in spheres]
        k = max(range(len(cells)), key=cells.__getitem__)
        field = f"{spheres[k][1].path}.slices" if 2 * cells[k] > sum(cells) else "objects"
        costs.append(Cost(field, MESH_CELL_BYTES * sum(cells), f"{len(spheres):,} sphere meshes of "
                                                                f"{sum(cells):,} cells in all"))
    return costs


def handout_diagrams() -> dict:
    """The handout's pictures of where the light is and of the modelview order (:mod:`cs451.stages.sphere.diagrams`)."""
    return part(__name__, "diagrams").PICTURES


#: the demo's keys: the student's S8 table (the handout's)
DEMO_KEYS = (("s", "Gouraud / Phong"), ("+ -", "tessellation"), ("q", "quits (through S8)"))


STAGE = Stage(
    name="sphere", number=1, title="The lit sphere", handout="01-sphere", tasks=TASKS, render=render, probes=PROBES,
    demo=run_demo, options_type=SphereOptions, draws=(Sphere, Group, PointLight, DirectionalLight), estimate=estimate,
    demo_keys=DEMO_KEYS,
    diagrams=handout_diagrams,
)
