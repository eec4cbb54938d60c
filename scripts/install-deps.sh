#!/usr/bin/env bash
# Installs what cdtgpu needs to build and test on Debian 12 (run as root, or with sudo available).
set -euo pipefail
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  cmake g++ make pkg-config git ca-certificates \
  libcgal-dev libtbb-dev libgmp-dev libmpfr-dev libboost-dev \
  libgeographiclib-dev libshp-dev libpng-dev libcli11-dev libspdlog-dev nlohmann-json3-dev \
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools glslang-tools \
  libgtest-dev libgmock-dev libbenchmark-dev python3-matplotlib \
  clang-14 libfuzzer-14-dev libclang-rt-14-dev libxml2-utils \
  libtiff-dev libgeotiff-dev libdeflate-dev gdal-bin \
  libopenmpi-dev openmpi-bin >/dev/null  # GeoTIFF in/out (gdal-bin: tests only); MPI: tiles over processes
