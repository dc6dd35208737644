# The kit in a container: Debian 12 with Mesa's EGL (llvmpipe), bubblewrap and Xvfb, set up by the README's
# own command. Build and run the tests:   docker build -t cs451-kit . && docker run --rm cs451-kit
# (the devcontainer in .devcontainer/ uses this file, for VS Code and GitHub Codespaces).
FROM debian:bookworm-slim

RUN apt-get update -qq \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
      python3 python3-venv ca-certificates libegl1 libegl-mesa0 libgl1-mesa-dri libglu1-mesa bubblewrap xvfb xauth \
 && rm -rf /var/lib/apt/lists/*

WORKDIR /kit
COPY . /kit
# the README's set-up command: the Python packages into .venv, then the main job (sphere.png)
RUN ./setup.sh
# the README's test command
CMD [".venv/bin/python", "-m", "pytest"]
