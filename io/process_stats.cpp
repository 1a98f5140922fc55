#include "io/process_stats.h"

#include <sys/resource.h>

namespace vdiso {

double peakRssMb() {
    struct rusage usage;
    if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
    return double(usage.ru_maxrss) / 1024.0;  // Linux reports kilobytes
}

}  // namespace vdiso
