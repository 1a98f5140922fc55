// Measurements of this process the statistics report.
#pragma once

namespace vdiso {

// Peak resident set size of the process so far, in MB (getrusage's ru_maxrss).
double peakRssMb();

}  // namespace vdiso
