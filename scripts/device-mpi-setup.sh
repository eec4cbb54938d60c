#!/usr/bin/env bash
# Open MPI on the lent GPU machine, which has none: its plugins and help files unpacked where the packed mpirun
# (orterun) looks for them, and `mpirun` on PATH. Pack it here first:
#   tar czf /tmp/ompi.tgz -P /usr/lib/x86_64-linux-gnu/openmpi /usr/lib/x86_64-linux-gnu/pmix2 \
#       /usr/share/openmpi /etc/openmpi /usr/share/pmix
#   ../shared/tools/devpack build/cdtgpu /usr/bin/orterun /usr/bin/orted -- /tmp/ompi.tgz
# then on the device (as root, OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 exported):
#   bash .devpack/run bash scripts/device-mpi-setup.sh
#   bash .devpack/run mpirun -n 2 --bind-to none cdtgpu triangulate ...
set -euo pipefail
d=${DEVPACK_DATA:?run it through .devpack/run}
[ -d /usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3 ] || tar xzf "$d/ompi.tgz" -P
ln -sf "$(dirname "$d")/bin/orterun" "$(dirname "$d")/bin/mpirun"
