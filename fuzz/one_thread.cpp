// One TBB thread in each fuzz worker: the readers parse on all cores, and `FORK=16 scripts/fuzz.sh` runs a
// worker per core, so a pool per worker would put 16 threads on every core (the 4 x H200 host's geotiff run
// made 4.2K executions a second with 16 workers, one worker alone here 8.5K). Linked into every target.
#include <tbb/global_control.h>

namespace {
const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
}  // namespace
