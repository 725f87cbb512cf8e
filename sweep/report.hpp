// The sweep's report.html: one self-contained page (inline SVG and CSS, no scripts) saying what
// was swept, how many cases ran and failed, and the fractional order λ — the LFOM fitted to each
// case's recording and the linearised pool's over the PRBS band — against each swept key.
#pragma once

#include <string>
#include <vector>

#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

// `rows`: the table's rows in case order (table.hpp), one per case.
std::string report_html(const SweepFile& sweep, const std::vector<std::string>& rows);

}  // namespace canalsim::sweep
