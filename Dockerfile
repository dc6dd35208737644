# The kit in a container: a minimal Debian 12 with Python, set up by the README's own command, which installs
# everything else (Mesa's EGL for headless rendering, bubblewrap, and the test tools: Xvfb, gcc, Chromium).
# Build and run the tests:   docker build -t cs451-kit . && docker run --rm cs451-kit
# (the devcontainer in .devcontainer/ uses this file, for VS Code and GitHub Codespaces).
FROM debian:bookworm-slim

RUN apt-get update -qq \
 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends python3 python3-venv ca-certificates \
 && rm -rf /var/lib/apt/lists/*

WORKDIR /kit
COPY . /kit
# the README's set-up command: system packages, the Python packages into .venv, the kernels, the main job
RUN ./setup.sh && rm -rf /var/lib/apt/lists/*
# the README's test command
CMD [".venv/bin/python", "-m", "pytest"]
