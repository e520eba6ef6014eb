#!/usr/bin/env bash
# Run here, once, before a GPU session's `device` call: what `must_show.sh` needs that the GPU machine lacks.
# That machine reaches no package index, and its image has numpy, scipy, pillow, imageio, matplotlib and
# tqdm but not these (the device tool's KINDS.md). The versions are the ones the tests pass with here.
#   .whl/  the wheels, for Python 3.12 on x86-64
#   .gl/   the GL loader libraries (glvnd, EGL), unpacked there over /
# Both folders are git-ignored; name them in the call's `carry`.
set -euo pipefail
cd "$(dirname "$0")/../.."
mkdir -p .whl .gl /tmp/amd64/partial
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 -d .whl \
  PyOpenGL==3.1.10 pyrender-maintained==1.0.1 trimesh==5.2.0 tomlkit==0.15.2 freetype-py==2.5.1 pyglet==2.1.19
apt_options=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64)
apt-get -qq "${apt_options[@]}" update
(cd .gl && apt-get -qq "${apt_options[@]}" download libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
du -sh .whl .gl
