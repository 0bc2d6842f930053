// The value readers the option table and ParseArgs share (options.cpp):
// strict, whole-string parses that refuse rather than clamp.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/core/status.h"

namespace vismask {

// "vismask: FLAG: expected EXPECTED, got 'VALUE'": every bad value's error.
Status BadValue(const std::string& flag, const std::string& value, const std::string& expected);

// A finite decimal number, the whole string (no leading space).
bool ParseNumber(const std::string& s, double* out);

// A count: decimal digits, or a number in scientific notation whose value
// is exactly an integer (1e6, 2.5e3, 10e-1; not 1.5 or 1e-1), read exactly
// in decimal (no rounding through double), at most 2^64 - 1.
bool ParseCount(const std::string& s, uint64_t* out);

// s split at each comma ("" gives one empty part).
std::vector<std::string> SplitCommas(const std::string& s);

}  // namespace vismask
