// Locale-independent number formatting for messages and output files: '.' as decimal point whatever the C or C++
// locale, the shortest text that reads back to the same double, "nan", "inf" and "-inf" for non-finite values.
#pragma once

#include <string>

namespace implicit_sim {

std::string FormatNumber(double value);

}  // namespace implicit_sim
