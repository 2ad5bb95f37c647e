// Reading comma-separated measurement files (no quoted fields): splitting a line and reading
// its cells, every failure naming the file, line and column.
#pragma once

#include <string>
#include <vector>

namespace twin {

/// Splits one CSV line at commas; a trailing comma gives a last empty field.
std::vector<std::string> SplitCsv(const std::string& line);

/// The cell as a finite number; throws InputError(where, ...) for text, NaN or infinity.
double CsvNumber(const std::string& text, const std::string& where);

/// The cell as a whole number in [0, 10^6]; throws InputError(where, ...) otherwise.
int CsvInteger(const std::string& text, const std::string& where);

}  // namespace twin
