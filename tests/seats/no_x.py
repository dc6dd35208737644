"""A machine without X: run a command with every X and GLX library, and the -dev packages' unversioned GL names,
unloadable, as on a GPU server with no X installed (DESIGN.md, "Environment facts").

Mesa's own EGL driver links a few X libraries (xcb, for its X11 platform), so those stay: what this hides is
everything else named like an X or GL library, found in the library folders, and not in the closure of what
Mesa's EGL and its software rasteriser load (``ldd``). Each hidden file is covered by /dev/null in a private
mount namespace (``unshare --mount``, root only), so loading it fails as a missing library would.
"""
from __future__ import annotations

import re
import shlex
import shutil
import subprocess
from pathlib import Path

LIBRARY_DIRS = [Path("/usr/lib/x86_64-linux-gnu"), Path("/usr/lib/aarch64-linux-gnu"), Path("/usr/lib")]
#: Names of X, GLX, GLUT and GL libraries (GLVND's libOpenGL and libEGL, which the kit loads, are matched, then kept;
#: GLU needs no X and stays)
X_OR_GL = re.compile(r"^lib(X\w*|xcb[\w-]*|GL|GLX\w*|glut|EGL|OpenGL|GLESv\w*)\.so(\.|$)")
#: What the kit may load: GLVND's EGL and desktop GL by their versioned names (cs451/gl.py, LINUX_LIBRARIES)
KEPT = {"libEGL.so.1", "libOpenGL.so.0"}


def _closure(paths: list[Path]) -> set[str]:
    """File names of every library ``paths`` load (ldd's transitive closure), the paths themselves included."""
    names = {p.name for p in paths}
    for path in paths:
        done = subprocess.run(["ldd", str(path)], capture_output=True, text=True)
        for line in done.stdout.splitlines():
            m = re.search(r"=>\s*(\S+)", line)
            if m and m.group(1) != "not":
                names.add(Path(m.group(1)).name)
                names.add(Path(m.group(1)).resolve().name)
    return names


def mesa_needs() -> set[str]:
    """What Mesa's EGL driver, its GBM and its software rasteriser load."""
    found = []
    for folder in LIBRARY_DIRS:
        found += [p for p in (folder / "libEGL_mesa.so.0", folder / "libgbm.so.1", folder / "libglapi.so.0",
                              folder / "dri" / "swrast_dri.so") if p.exists()]
    return _closure(found)


def hidden_libraries() -> list[Path]:
    """The library files to make unloadable (links too: each name a loader may open)."""
    needed = mesa_needs() | KEPT
    hidden = []
    for folder in LIBRARY_DIRS:
        if not folder.is_dir():
            continue
        needed |= {(folder / name).resolve().name for name in KEPT if (folder / name).exists()}
        for path in sorted(folder.iterdir()):
            if X_OR_GL.match(path.name) and path.name not in needed and path.resolve().name not in needed:
                hidden.append(path)
    return hidden


def hiding(paths: list[Path], command: list[str]) -> list[str]:
    """``command`` run with each file of ``paths`` covered by /dev/null (needs root and util-linux's unshare)."""
    if not shutil.which("unshare"):
        raise RuntimeError("unshare (util-linux) is needed to hide libraries")
    binds = "\n".join(f"mount --bind /dev/null {shlex.quote(str(p))}" for p in paths)
    script = f"set -e\n{binds}\nexec \"$@\"\n"
    return ["unshare", "--mount", "--propagation", "private", "sh", "-c", script, "sh", *command]


def without_x(command: list[str]) -> list[str]:
    """``command`` run with the X and GLX libraries hidden."""
    return hiding(hidden_libraries(), command)
