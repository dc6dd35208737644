#!/usr/bin/env bash
# Run here, once, before a session's device check (see bench/gpu/README.md): fetches what the GPU machine lacks
# into the repository's ignored .gl/ (EGL and GL loaders, amd64 .debs) and .whl/ (the kit's wheels for its
# Python 3.12), which `run` carries there. Nothing here is needed by the kit itself.
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"
mkdir -p .gl .whl /tmp/amd64/partial
apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
apt-get "${apt_opts[@]}" update -qq
(cd .gl && apt-get "${apt_opts[@]}" download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
# The machine's image has numpy, scipy, Pillow, networkx, imageio, six, tqdm, Jinja2 and numba; these it lacks.
# Versions are the pins of pyproject.toml where it pins, and what this checkout's venv holds otherwise.
platforms=(--platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64
           --platform manylinux2014_x86_64 --platform manylinux1_x86_64)
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp "${platforms[@]}" \
    -d .whl moderngl==5.13.0 glcontext==3.1.0 freetype-py==2.5.1 glfw==2.11.0
# pure Python: PyOpenGL 3.1.0 (pyrender's pin) is published as a source archive only, so build each wheel here
python3 -m pip wheel -q --no-deps -w .whl pyrender==0.1.45 PyOpenGL==3.1.0 trimesh==5.2.0 pyglet==2.1.19
du -sh .gl .whl
