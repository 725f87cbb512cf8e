// The sweep's table (table.csv, docs/sweep.md "The table"): one tidy row per case,
//
//   case,point,experiment,<each varied key>,status,message,<computed columns>
//
// status "ok" or "failed"; message the error of a failed case (its computed cells then empty) or
// the warnings of an ok one. Numbers are written exactly (cases.hpp, exact_number: the value
// simulated, bit for bit), "inf"/"-inf" where infinite, and an empty cell where not defined. A cell holding a comma,
// a quote or a line break is quoted as RFC 4180 says.
#pragma once

#include <string>
#include <vector>

#include "sweep/cases.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

std::vector<std::string> table_columns(const SweepFile& sweep);
// The header line of the table (with its line break).
std::string table_header(const SweepFile& sweep);

std::string number_cell(double value);

// One line of CSV (with its line break), and its cells back.
std::string csv_line(const std::vector<std::string>& cells);
std::vector<std::string> split_csv_line(const std::string& line);

// The cells every row starts with, which depend on the case alone: case, point, experiment and
// the values of the varied keys.
std::vector<std::string> case_cells(const SweepFile& sweep, const Case& c);

// A finished case's row: `computed` holds one cell per computed column (ignored when failed).
std::string ok_row(const SweepFile& sweep, const Case& c, const std::vector<std::string>& computed,
                   const std::string& warnings);
std::string failed_row(const SweepFile& sweep, const Case& c, const std::string& error);
// Whether a row's status is "ok".
bool row_ok(const SweepFile& sweep, const std::string& row);

}  // namespace canalsim::sweep
