// Reading the project's CSV files (pose plans, measurements) row by row, so a large file
// is streamed in bounded memory. Tolerates what hand-edited and exported files contain:
// a UTF-8 byte-order mark, CRLF line endings, '#' comment lines, blank lines and spaces
// around cells. Everything else wrong is an InputError naming file, line and column.
#pragma once

#include <fstream>
#include <functional>
#include <istream>
#include <string>
#include <vector>

namespace cablecal {

struct CsvRow {
  const std::string* path = nullptr;
  int line = 0;  // 1-based line number in the file
  int header_line = 0;  // the header's (ForEachCsvRowByName and ...Strict only)
  const std::vector<std::string>* header = nullptr;
  std::vector<std::string> cells;
  // Per column of `header`: false for an optional column the file does not have (its cell is
  // then empty). Empty means every column is there.
  std::vector<bool> present;

  // The cell of column `col` as a finite double; InputError "file:line: column 'x': ..." otherwise.
  double Number(int col) const;
  // The cell as a positive integer id.
  int PositiveInt(int col) const;
  std::string Where() const;
};

// `path` opened for reading: InputError naming it when it is a folder (a stream opens one on
// Linux and then fails at the first read, which read as "a line longer than ..."), or cannot be
// opened.
std::ifstream OpenCsvFile(const std::string& path);

// Reads `path`; the first non-comment line must equal `expected_header` (cells compared
// after trimming). Calls `on_row` for every data row, which has exactly as many cells as
// the header. Throws InputError for a missing file, a wrong header, a wrong cell count or
// a file with no data rows, and for a line longer than kMaxCsvLineBytes (a file that is not
// a CSV, or /dev/zero, is refused there instead of read into memory).
void ForEachCsvRow(const std::string& path, const std::vector<std::string>& expected_header,
                   const std::function<void(const CsvRow&)>& on_row);
// The same from a stream; `name` stands for the file in messages.
void ForEachCsvRow(std::istream& in, const std::string& name, const std::vector<std::string>& expected_header,
                   const std::function<void(const CsvRow&)>& on_row);
// The same, where the header may also be `expected_header` followed by `optional_trailing`
// (all of them): rows then have that many cells, and row.header is the header found.
void ForEachCsvRow(std::istream& in, const std::string& name, const std::vector<std::string>& expected_header,
                   const std::vector<std::string>& optional_trailing, const std::function<void(const CsvRow&)>& on_row);

// A lab's file, read by column name: the header must name every column of `required` once,
// in any order, and may name those of `optional` (a sensor the lab does not have); other
// columns are ignored and `on_ignored` (if any) hears their names once. Cells are split at
// `delimiter` (',', ';' or a tab). Rows reach `on_row` with their cells in the order of
// `required` then `optional` (row.header), row.present saying which optional columns the file
// has. An empty cell is refused by CsvRow with its line and column.
void ForEachCsvRowByName(std::istream& in, const std::string& name, char delimiter,
                         const std::vector<std::string>& required, const std::vector<std::string>& optional,
                         const std::function<void(const std::vector<std::string>&)>& on_ignored,
                         const std::function<void(const CsvRow&)>& on_row);

// The same for a file cablecal wrote, where a column it does not know is a mistake (a
// misspelt or another kind's column): refused naming the header's line and the column, and
// what `explain` (if given) says of the unknown columns, appended.
void ForEachCsvRowByNameStrict(std::istream& in, const std::string& name, char delimiter,
                               const std::vector<std::string>& required, const std::vector<std::string>& optional,
                               const std::function<void(const CsvRow&)>& on_row,
                               const std::function<std::string(const std::vector<std::string>&)>& explain = nullptr);

constexpr std::size_t kMaxCsvLineBytes = 1 << 16;

std::string JoinCsv(const std::vector<std::string>& cells);

}  // namespace cablecal
