#include "util/parallel.h"

#include <tbb/global_control.h>

namespace shgi {

int max_threads() {
    return static_cast<int>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace shgi
