// Pieces of the self-contained HTML reports (reproduce, diagnose, calibrate).
#pragma once

#include <string>

namespace canalsim::html {

// Text made safe for HTML element content and attribute values: & < > " escaped.
std::string escape(const std::string& text);

}  // namespace canalsim::html
