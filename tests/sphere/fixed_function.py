"""The real OpenGL 1.x fixed-function pipeline, headless: a ground truth for stage 1's shaders.

Nothing here comes from reference/: the sphere is drawn as freeglut's
``glutSolidSphere`` draws it (fghGenerateSphere's vertices and normals, one
triangle strip per stack), the camera is set with GLU's ``gluPerspective`` and
``gluLookAt`` (the DESIGN.md matrices where libGLU is missing), and the
lighting is whatever Mesa's fixed-function pipeline computes from
``glLightfv``, ``glLightModelfv`` and ``glMaterialfv``.

The context is an OpenGL compatibility-profile context made with raw EGL
through PyOpenGL on Mesa's surfaceless platform, drawn into a framebuffer
object (RGBA8 + 24-bit depth). It is made once and kept; every render puts
back whatever EGL context was current before (moderngl's, say), so the
engine's own contexts never draw into this one or the other way round.

Use :func:`available` (``(ok, reason)``) before :func:`render`; a test skips
with that reason where EGL or a compatibility context cannot be had.
No tests in here.

Mesa is a truth only where it follows the specification: with GL_SHININESS 0
and a positional light with attenuation other than (1, 0, 0), Mesa 22.3.6's
fixed-function specular term is att·(n·L)^(n·L), not att (measured; see
tests/sphere/test_sphere_truth.py).
"""
from __future__ import annotations

import ctypes
import os

import numpy as np

from cs451.scene import DirectionalLight, Group, PointLight, Scene, Sphere

# PyOpenGL picks its platform when OpenGL is first imported (as cs451/pyrender_shim.py does);
# Mesa's libEGL reads EGL_PLATFORM when a display is opened.
if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
    os.environ.setdefault("EGL_PLATFORM", "surfaceless")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

EGL_PLATFORM_SURFACELESS_MESA = 0x31DD

#: How the camera matrices were made in the last render: "GLU" or "DESIGN.md formulas".
matrices_from = ""

_state: dict = {}


class Unavailable(RuntimeError):
    """No OpenGL compatibility context through EGL here."""


def _egl_modules():
    try:
        import OpenGL.platform
        name = type(OpenGL.platform.PLATFORM).__name__
        if "EGL" not in name:
            raise Unavailable(f"PyOpenGL runs on its {name}, not EGL (PYOPENGL_PLATFORM must be 'egl' "
                              "before OpenGL is first imported)")
        from OpenGL import EGL as egl
        from OpenGL import GL as gl
    except Unavailable:
        raise
    except Exception as err:  # ImportError, missing libEGL, ...
        raise Unavailable(f"PyOpenGL's EGL platform does not load: {type(err).__name__}: {err}") from None
    return egl, gl


def _display(egl):
    """Mesa's surfaceless display, asked for by name; else the default display (EGL_PLATFORM=surfaceless)."""
    try:
        exts = egl.eglQueryString(egl.EGL_NO_DISPLAY, egl.EGL_EXTENSIONS) or b""
    except Exception:
        exts = b""
    if b"EGL_MESA_platform_surfaceless" in exts and b"EGL_EXT_platform_base" in exts:
        address = egl.eglGetProcAddress("eglGetPlatformDisplayEXT")
        if address:
            proto = ctypes.CFUNCTYPE(egl.EGLDisplay, ctypes.c_uint, ctypes.c_void_p, ctypes.c_void_p)
            dpy = proto(address)(EGL_PLATFORM_SURFACELESS_MESA, None, None)
            if dpy:
                return dpy
    return egl.eglGetDisplay(egl.EGL_DEFAULT_DISPLAY)


def _create():
    egl, gl = _egl_modules()
    try:
        dpy = _display(egl)
        major, minor = egl.EGLint(), egl.EGLint()
        if not dpy or not egl.eglInitialize(dpy, ctypes.pointer(major), ctypes.pointer(minor)):
            raise Unavailable("eglInitialize failed on the surfaceless display")
        if not egl.eglBindAPI(egl.EGL_OPENGL_API):
            raise Unavailable("eglBindAPI(EGL_OPENGL_API) failed: this EGL offers no desktop OpenGL")
        config = egl.EGLConfig()
        count = egl.EGLint()
        attrs = (egl.EGLint * 3)(egl.EGL_RENDERABLE_TYPE, egl.EGL_OPENGL_BIT, egl.EGL_NONE)
        egl.eglChooseConfig(dpy, attrs, ctypes.pointer(config), 1, ctypes.pointer(count))
        if count.value < 1:  # surfaceless Mesa offers no configs; EGL_KHR_no_config_context makes that fine
            config = egl.EGLConfig()  # a null EGLConfig is EGL_NO_CONFIG_KHR
        # A 2.1 context: EGL gives the compatibility profile (Mesa: 4.5 compatibility) for versions < 3.2.
        ctx_attrs = (egl.EGLint * 5)(egl.EGL_CONTEXT_MAJOR_VERSION, 2, egl.EGL_CONTEXT_MINOR_VERSION, 1,
                                     egl.EGL_NONE)
        ctx = egl.eglCreateContext(dpy, config, egl.EGL_NO_CONTEXT, ctx_attrs)
        if not ctx:
            raise Unavailable(f"eglCreateContext for an OpenGL 2.1 compatibility context failed "
                              f"(EGL error 0x{egl.eglGetError():x})")
    except Unavailable:
        raise
    except Exception as err:
        raise Unavailable(f"EGL context creation failed: {type(err).__name__}: {err}") from None
    _state.update(egl=egl, gl=gl, dpy=dpy, ctx=ctx)
    with _Current():
        version = gl.glGetString(gl.GL_VERSION) or b""
        renderer = gl.glGetString(gl.GL_RENDERER) or b""
        _state["version"] = f"{renderer.decode()} / {version.decode()}"
        try:
            gl.glMatrixMode(gl.GL_MODELVIEW)
            gl.glLoadIdentity()
            if gl.glGetError() != gl.GL_NO_ERROR:
                raise Unavailable(f"the context is not a compatibility profile ({_state['version']})")
        except Unavailable:
            raise
        except Exception as err:
            raise Unavailable(f"fixed-function calls fail in this context ({_state['version']}): {err}") from None


class _Current:
    """Make the fixed-function context current; put back the caller's EGL context afterwards."""

    def __enter__(self):
        egl = _state["egl"]
        self.saved = (egl.eglGetCurrentDisplay(), egl.eglGetCurrentSurface(egl.EGL_DRAW),
                      egl.eglGetCurrentSurface(egl.EGL_READ), egl.eglGetCurrentContext())
        if not egl.eglMakeCurrent(_state["dpy"], egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE, _state["ctx"]):
            raise Unavailable("eglMakeCurrent failed for the fixed-function context")
        return self

    def __exit__(self, *exc):
        egl = _state["egl"]
        dpy, draw, read, ctx = self.saved
        if ctx:
            egl.eglMakeCurrent(dpy, draw, read, ctx)
        else:
            egl.eglMakeCurrent(_state["dpy"], egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE, egl.EGL_NO_CONTEXT)
        return False


def available() -> tuple[bool, str]:
    """Whether a fixed-function context can be had, and if not, why (for pytest.skip)."""
    if "error" in _state:
        return False, _state["error"]
    if "ctx" not in _state:
        try:
            _create()
        except Unavailable as err:
            _state.clear()
            _state["error"] = f"no OpenGL compatibility context through EGL: {err}"
            return False, _state["error"]
    return True, _state["version"]


# --- freeglut's glutSolidSphere ----------------------------------------------

def freeglut_sphere(radius: float, slices: int, stacks: int) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """fghGenerateSphere's vertices and normals, and fghDrawGeometrySolid's strip indices (one per stack)."""
    verts = [(0.0, 0.0, 1.0)]
    for i in range(1, stacks):
        t = np.pi * i / stacks
        for j in range(slices):
            p = -2.0 * np.pi * j / slices
            verts.append((np.cos(p) * np.sin(t), np.sin(p) * np.sin(t), np.cos(t)))
    verts.append((0.0, 0.0, -1.0))
    normals = np.array(verts)
    positions = radius * normals
    n = len(positions)
    strips = [np.array([v for j in range(slices + 1) for v in (j % slices + 1, 0)])]  # top: (1,0), (2,0)...
    for i in range(stacks - 2):
        offset = 1 + i * slices
        strips.append(np.array([v for j in range(slices + 1)
                                for v in (offset + j % slices + slices, offset + j % slices)]))
    offset = 1 + (stacks - 2) * slices
    strips.append(np.array([v for j in range(slices + 1) for v in (n - 1, offset + j % slices)]))
    return positions, normals, strips


# --- drawing -------------------------------------------------------------------

def _camera_matrices(gl, scene: Scene, aspect: float) -> None:
    global matrices_from
    cam = scene.camera
    try:
        from OpenGL import GLU
        gl.glMatrixMode(gl.GL_PROJECTION)
        gl.glLoadIdentity()
        GLU.gluPerspective(cam.fovy, aspect, cam.near, cam.far)
        gl.glMatrixMode(gl.GL_MODELVIEW)
        gl.glLoadIdentity()
        GLU.gluLookAt(*cam.eye, *cam.center, *cam.up)
        matrices_from = "GLU"
        return
    except Exception:
        pass
    f = 1.0 / np.tan(np.radians(cam.fovy) / 2.0)
    proj = np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (cam.far + cam.near) / (cam.near - cam.far), 2 * cam.far * cam.near / (cam.near - cam.far)],
                     [0, 0, -1, 0]])
    eye, center, up = (np.asarray(v, float) for v in (cam.eye, cam.center, cam.up))
    fw = (center - eye) / np.linalg.norm(center - eye)
    s = np.cross(fw, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, fw)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = s, u, -fw
    view[:3, 3] = -view[:3, :3] @ eye
    gl.glMatrixMode(gl.GL_PROJECTION)
    gl.glLoadMatrixd(proj.T.ravel())
    gl.glMatrixMode(gl.GL_MODELVIEW)
    gl.glLoadMatrixd(view.T.ravel())
    matrices_from = "DESIGN.md formulas"


def _rgba(v) -> list[float]:
    return [float(v[0]), float(v[1]), float(v[2]), 1.0]


def _set_light(gl, index: int, light) -> None:
    """glLightfv for one light; the view matrix is on the modelview stack."""
    name = gl.GL_LIGHT0 + index
    gl.glEnable(name)
    gl.glLightfv(name, gl.GL_AMBIENT, _rgba(light.ambient))
    gl.glLightfv(name, gl.GL_DIFFUSE, _rgba(light.diffuse))
    gl.glLightfv(name, gl.GL_SPECULAR, _rgba(light.specular))
    if isinstance(light, PointLight):
        position = [*map(float, light.position), 1.0]
        k = light.attenuation
        gl.glLightf(name, gl.GL_CONSTANT_ATTENUATION, float(k[0]))
        gl.glLightf(name, gl.GL_LINEAR_ATTENUATION, float(k[1]))
        gl.glLightf(name, gl.GL_QUADRATIC_ATTENUATION, float(k[2]))
    else:  # GL keeps the direction towards the light, w = 0
        position = [*(-float(c) for c in light.direction), 0.0]
    # GL transforms the position by the modelview current at glLightfv time.
    gl.glPushMatrix()
    if light.space == "eye":
        gl.glLoadIdentity()
    gl.glLightfv(name, gl.GL_POSITION, position)
    gl.glPopMatrix()


def _draw_sphere(gl, sphere: Sphere, mesh=None) -> None:
    gl.glPushMatrix()
    gl.glTranslated(*map(float, sphere.center))
    if mesh is None:  # glutSolidSphere(radius, slices, stacks)
        positions, normals, strips = freeglut_sphere(sphere.radius, sphere.slices, sphere.stacks)
        for strip in strips:
            gl.glBegin(gl.GL_TRIANGLE_STRIP)
            for k in strip:
                gl.glNormal3d(*normals[k])
                gl.glVertex3d(*positions[k])
            gl.glEnd()
    else:  # a given (positions, normals, triangles) mesh
        positions, normals, triangles = mesh
        gl.glBegin(gl.GL_TRIANGLES)
        for k in np.asarray(triangles).ravel():
            gl.glNormal3d(*map(float, normals[k]))
            gl.glVertex3d(*map(float, positions[k]))
        gl.glEnd()
    gl.glPopMatrix()


def _apply(gl, call: tuple) -> None:
    """One modelview call, made with OpenGL's own glTranslated, glRotated, glScaled, glPushMatrix, glPopMatrix."""
    name, *args = call
    if name == "push":
        gl.glPushMatrix()
    elif name == "pop":
        gl.glPopMatrix()
    elif name == "translate":
        gl.glTranslated(*map(float, args))
    elif name == "rotate":
        gl.glRotated(*map(float, args))
    elif name == "scale":
        gl.glScaled(*map(float, args))
    else:
        raise ValueError(f"not a modelview call: {call!r}")


def _draw_objects(gl, scene: Scene, objects: list, meshes) -> None:
    """Spheres and groups as a fixed-function program draws them: a group's transforms between push and pop."""
    for obj in objects:
        if isinstance(obj, Group):
            gl.glPushMatrix()
            for transform in obj.transform:
                _apply(gl, transform.call)
            _draw_objects(gl, scene, obj.objects, meshes)
            gl.glPopMatrix()
            continue
        m = scene.material(obj.material)
        face = gl.GL_FRONT_AND_BACK
        gl.glMaterialfv(face, gl.GL_AMBIENT, _rgba(m.ambient))
        gl.glMaterialfv(face, gl.GL_DIFFUSE, _rgba(m.diffuse))
        gl.glMaterialfv(face, gl.GL_SPECULAR, _rgba(m.specular))
        gl.glMaterialfv(face, gl.GL_EMISSION, _rgba(m.emission))
        gl.glMaterialf(face, gl.GL_SHININESS, float(m.shininess))
        _draw_sphere(gl, obj, None if meshes is None else next(meshes))


def model_view_matrices(view: np.ndarray, calls: list) -> np.ndarray:
    """What OpenGL's modelview stack holds at each ``draw`` of ``calls``, starting from ``view``: (draws, 4, 4).

    Mesa keeps the stack in float32, so its matrices agree with float64 ones to about 1e-7 relative.
    """
    ok, reason = available()
    if not ok:
        raise Unavailable(reason)
    gl = _state["gl"]
    drawn = []
    with _Current():
        gl.glMatrixMode(gl.GL_MODELVIEW)
        gl.glPushMatrix()
        try:
            gl.glLoadMatrixd(np.asarray(view, dtype=np.float64).T.ravel())
            for call in calls:
                if call[0] == "draw":
                    drawn.append(np.asarray(gl.glGetDoublev(gl.GL_MODELVIEW_MATRIX), dtype=np.float64).reshape(4, 4).T)
                else:
                    _apply(gl, tuple(call))
            error = gl.glGetError()
            if error != gl.GL_NO_ERROR:
                raise RuntimeError(f"OpenGL error 0x{int(error):x} in the modelview calls")
        finally:
            gl.glPopMatrix()
    return np.array(drawn).reshape(-1, 4, 4)


def render(scene: Scene, size: tuple[int, int] | None = None, meshes: list | None = None) -> np.ndarray:
    """The scene's spheres drawn by the fixed-function pipeline: (h, w, 3) floats in [0, 1], top row first.

    ``meshes`` optionally replaces freeglut's sphere by (positions, normals, triangles) per sphere.
    Raises :class:`Unavailable` where no compatibility context can be had.
    """
    ok, reason = available()
    if not ok:
        raise Unavailable(reason)
    gl = _state["gl"]
    width, height = size or (scene.image.width, scene.image.height)
    opts = scene.options.get("sphere", {})
    local_viewer = bool(opts.get("local_viewer", True))
    lights = [l for l in scene.lights if isinstance(l, (PointLight, DirectionalLight))]
    if len(lights) > 8:
        raise ValueError("the fixed-function pipeline has 8 lights")
    with _Current():
        fbo = gl.glGenFramebuffers(1)
        rbs = gl.glGenRenderbuffers(2)
        color, depth = int(rbs[0]), int(rbs[1])
        try:
            gl.glBindFramebuffer(gl.GL_FRAMEBUFFER, fbo)
            gl.glBindRenderbuffer(gl.GL_RENDERBUFFER, color)
            gl.glRenderbufferStorage(gl.GL_RENDERBUFFER, gl.GL_RGBA8, width, height)
            gl.glFramebufferRenderbuffer(gl.GL_FRAMEBUFFER, gl.GL_COLOR_ATTACHMENT0, gl.GL_RENDERBUFFER, color)
            gl.glBindRenderbuffer(gl.GL_RENDERBUFFER, depth)
            gl.glRenderbufferStorage(gl.GL_RENDERBUFFER, gl.GL_DEPTH_COMPONENT24, width, height)
            gl.glFramebufferRenderbuffer(gl.GL_FRAMEBUFFER, gl.GL_DEPTH_ATTACHMENT, gl.GL_RENDERBUFFER, depth)
            status = gl.glCheckFramebufferStatus(gl.GL_FRAMEBUFFER)
            if status != gl.GL_FRAMEBUFFER_COMPLETE:
                raise Unavailable(f"framebuffer incomplete (0x{int(status):x})")
            gl.glPushAttrib(gl.GL_ALL_ATTRIB_BITS)
            try:
                gl.glViewport(0, 0, width, height)
                gl.glClearColor(*map(float, scene.image.background), 1.0)
                gl.glClearDepth(1.0)
                gl.glClear(gl.GL_COLOR_BUFFER_BIT | gl.GL_DEPTH_BUFFER_BIT)
                gl.glEnable(gl.GL_DEPTH_TEST)
                gl.glDepthFunc(gl.GL_LESS)
                gl.glShadeModel(gl.GL_SMOOTH)
                gl.glDisable(gl.GL_CULL_FACE)
                gl.glDisable(gl.GL_COLOR_MATERIAL)
                gl.glDisable(gl.GL_DITHER)  # 8-bit output without dithering, as moderngl's FBO
                gl.glEnable(gl.GL_LIGHTING)
                gl.glLightModelfv(gl.GL_LIGHT_MODEL_AMBIENT, _rgba(scene.ambient))
                gl.glLightModeli(gl.GL_LIGHT_MODEL_LOCAL_VIEWER, int(local_viewer))
                gl.glLightModeli(gl.GL_LIGHT_MODEL_TWO_SIDE, 0)
                _camera_matrices(gl, scene, width / max(height, 1))
                for i in range(8):
                    gl.glDisable(gl.GL_LIGHT0 + i)
                for i, light in enumerate(lights):
                    _set_light(gl, i, light)
                gl.glEnable(gl.GL_NORMALIZE)  # glScale'd groups: GL renormalises the transformed normals
                _draw_objects(gl, scene, scene.objects, iter(meshes) if meshes is not None else None)
                gl.glFinish()
                gl.glPixelStorei(gl.GL_PACK_ALIGNMENT, 1)
                gl.glReadBuffer(gl.GL_COLOR_ATTACHMENT0)
                data = gl.glReadPixels(0, 0, width, height, gl.GL_RGB, gl.GL_UNSIGNED_BYTE)
                error = gl.glGetError()
                if error != gl.GL_NO_ERROR:
                    raise RuntimeError(f"OpenGL error 0x{int(error):x} in the fixed-function render")
            finally:
                gl.glPopAttrib()
        finally:
            gl.glBindFramebuffer(gl.GL_FRAMEBUFFER, 0)
            gl.glDeleteRenderbuffers(2, rbs)
            gl.glDeleteFramebuffers(1, [fbo])
    if isinstance(data, (bytes, bytearray)):
        pixels = np.frombuffer(data, dtype=np.uint8)
    else:
        pixels = np.asarray(data, dtype=np.uint8)
    pixels = pixels.reshape(height, width, 3)
    return np.flipud(pixels).astype(np.float64) / 255.0
