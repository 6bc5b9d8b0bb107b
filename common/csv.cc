#include "common/csv.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/format.h"

namespace cablecal {
namespace {

std::string Trim(const std::string& s) {
  const char* ws = " \t\r";
  const std::size_t a = s.find_first_not_of(ws);
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(ws) - a + 1);
}

std::vector<std::string> Split(const std::string& line, char delimiter) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(delimiter, start);
    cells.push_back(Trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

}  // namespace

std::string JoinCsv(const std::vector<std::string>& cells) {
  std::string s;
  for (std::size_t i = 0; i < cells.size(); ++i) s += (i ? "," : "") + cells[i];
  return s;
}

std::string CsvRow::Where() const { return *path + ":" + std::to_string(line); }

double CsvRow::Number(int col) const {
  double v = 0.0;
  if (cells[col].empty()) throw InputError(Where(), "column '" + (*header)[col] + "'", "is empty: a reading is missing");
  if (!ParseFiniteDouble(cells[col], &v)) {
    const bool decimal_comma = cells[col].find(',') != std::string::npos;
    throw InputError(Where(), "column '" + (*header)[col] + "'",
                     "must be a finite number (got '" + cells[col] + "')" +
                         (decimal_comma ? ": a decimal comma? numbers use '.'" : ""));
  }
  return v;
}

int CsvRow::PositiveInt(int col) const {
  const std::string& s = cells[col];
  const bool digits = !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
  const std::size_t significant = digits ? s.size() - std::min(s.find_first_not_of('0'), s.size()) : 0;
  if (digits && significant > 9) {  // positive, but beyond an id's nine digits
    throw InputError(Where(), "column '" + (*header)[col] + "'",
                     "must be a positive integer of at most 9 digits (got '" + s + "')");
  }
  if (!digits || std::stoi(s) < 1) {
    throw InputError(Where(), "column '" + (*header)[col] + "'", "must be a positive integer (got '" + s + "')");
  }
  return std::stoi(s);
}

std::ifstream OpenCsvFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, "", "is a folder, not a CSV file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file");
  return in;
}

void ForEachCsvRow(const std::string& path, const std::vector<std::string>& expected_header,
                   const std::function<void(const CsvRow&)>& on_row) {
  std::ifstream in = OpenCsvFile(path);
  ForEachCsvRow(in, path, expected_header, on_row);
}

void ForEachCsvRow(std::istream& in, const std::string& path, const std::vector<std::string>& expected_header,
                   const std::function<void(const CsvRow&)>& on_row) {
  ForEachCsvRow(in, path, expected_header, {}, on_row);
}

namespace {

// std::getline bounded by kMaxCsvLineBytes. False at the end of the input.
bool ReadLine(std::istream& in, std::string& line, const std::string& path, int line_no) {
  static thread_local std::vector<char> buffer(kMaxCsvLineBytes + 2);
  in.getline(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  const std::streamsize count = in.gcount();
  if (count == 0 && in.eof()) return false;
  if (in.fail() && !in.eof()) {  // the buffer filled before a newline
    throw InputError(path + ":" + std::to_string(line_no), "",
                     "a line longer than " + std::to_string(kMaxCsvLineBytes) + " bytes: is this a CSV file?");
  }
  // gcount counts the newline when one was extracted (not at the end of the input).
  line.assign(buffer.data(), static_cast<std::size_t>(count - (in.eof() ? 0 : 1)));
  in.clear(in.rdstate() & std::ios::eofbit);  // a last line without newline sets failbit too
  return true;
}

// Every content line of a CSV: a UTF-8 byte-order mark, blank lines and '#' comment lines
// skipped, the line trimmed and split at `delimiter`. `on_line` gets the line number, the
// trimmed line and its cells.
void ForEachCsvLine(std::istream& in, const std::string& path, char delimiter,
                    const std::function<void(int, const std::string&, std::vector<std::string>&)>& on_line) {
  std::string line;
  int line_no = 0;
  bool content = false;  // a content line seen (the header)
  while (ReadLine(in, line, path, line_no + 1)) {
    ++line_no;
    // A UTF-8 byte-order mark: at the file's start (Excel's "CSV UTF-8"), or before the header
    // when a lab pasted a BOM-marked header below the comment lines.
    if (!content && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    content = true;
    std::vector<std::string> cells = Split(trimmed, delimiter);
    on_line(line_no, trimmed, cells);
  }
  if (in.bad()) throw InputError(path, "", "read error");
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Plans and measurement files have one dl<i> column per cable: a header whose dl columns
// differ in number from the robot's is a file for a robot with another cable count. The
// message part that says so, or "" when the counts agree or either has none.
std::string OtherCableCount(const std::vector<std::string>& wanted, const std::vector<std::string>& got) {
  // In any case: 'DL1' is a cable's column typed in capitals (refused with a hint), not another robot's.
  // A dl column given twice ('dl1,dl1') is a repeated column, which the caller names, not
  // another cable count: -1 then.
  const auto cable_columns = [](const std::vector<std::string>& names) {
    std::set<std::string> distinct;
    int count = 0;
    for (const std::string& c : names) {
      if (c.size() > 2 && (c[0] == 'd' || c[0] == 'D') && (c[1] == 'l' || c[1] == 'L') &&
          c.find_first_not_of("0123456789", 2) == std::string::npos) {
        distinct.insert(c);
        ++count;
      }
    }
    return static_cast<int>(distinct.size()) == count ? count : -1;
  };
  const int want = cable_columns(wanted), have = cable_columns(got);
  if (want <= 0 || have <= 0 || want == have) return "";
  // Fewer columns, not simply the last cables' (dl1,dl2,dl4,... for 8 cables): a column dropped
  // as likely as another robot's file, so the missing ones are named.
  std::string message = "the file has columns for " + std::to_string(have) + " cables, the robot has " + std::to_string(want);
  if (have < want) {
    std::set<std::string> present;
    for (const std::string& c : got) present.insert(Lower(c));
    std::string missing;
    bool only_the_last = true;
    for (const std::string& c : wanted) {
      if (c.size() <= 2 || c.compare(0, 2, "dl") != 0 || present.count(c)) continue;
      missing += (missing.empty() ? "'" : ", '") + c + "'";
      only_the_last = only_the_last && std::atoi(c.c_str() + 2) > have;
    }
    if (!missing.empty() && !only_the_last) {
      return message + " (" + missing + " missing): a column dropped, or a file for another robot?";
    }
  }
  return message + ": a file for another robot?";
}

// Header cells that name a missing column in another case ('Pose' for 'pose'): names are
// compared exactly, so the likely cause is said. "" when none does.
std::string CaseHint(const std::vector<std::string>& missing, const std::vector<std::string>& cells) {
  std::string pairs;
  for (const std::string& name : missing) {
    for (const std::string& cell : cells) {
      if (cell != name && Lower(cell) == Lower(name)) {
        pairs += (pairs.empty() ? "" : ", ") + std::string("'") + name + "' for '" + cell + "'";
        break;
      }
    }
  }
  return pairs.empty() ? "" : " (column names are lower case: did you mean " + pairs + "?)";
}

}  // namespace

void ForEachCsvRow(std::istream& in, const std::string& path, const std::vector<std::string>& expected_header,
                   const std::vector<std::string>& optional_trailing, const std::function<void(const CsvRow&)>& on_row) {
  std::vector<std::string> full_header = expected_header;
  full_header.insert(full_header.end(), optional_trailing.begin(), optional_trailing.end());
  std::vector<std::string> found_header = expected_header;
  bool have_header = false;
  int rows = 0;
  CsvRow row;
  row.path = &path;
  row.header = &found_header;
  ForEachCsvLine(in, path, ',', [&](int line_no, const std::string& trimmed, std::vector<std::string>& cells) {
    if (!have_header) {
      if (!optional_trailing.empty() && cells == full_header) found_header = full_header;
      if (cells != found_header) {
        std::string other = OtherCableCount(expected_header, cells);
        if (other.empty()) {
          // Name what is missing (a column dropped), else the two headers alone say it.
          std::vector<std::string> missing;
          for (const std::string& name : expected_header) {
            if (std::find(cells.begin(), cells.end(), name) == cells.end()) missing.push_back(name);
          }
          constexpr std::size_t kNamed = 3;
          if (!missing.empty()) {
            const bool more = missing.size() > kNamed;
            missing.resize(std::min(kNamed, missing.size()));
            other = QuotedList(missing) + (more ? ", ..." : "") + " missing";
          }
        }
        throw InputError(path + ":" + std::to_string(line_no), "header",
                         "expected '" + JoinCsv(expected_header) + "', got '" + trimmed + "'" +
                             (other.empty() ? "" : " (" + other + ")"));
      }
      have_header = true;
      return;
    }
    if (cells.size() != found_header.size()) {
      throw InputError(path + ":" + std::to_string(line_no), "",
                       "expected " + std::to_string(found_header.size()) + " columns, got " +
                           std::to_string(cells.size()));
    }
    row.line = line_no;
    row.cells = std::move(cells);
    on_row(row);
    ++rows;
  });
  if (!have_header) throw InputError(path, "", "is empty: no header line '" + JoinCsv(expected_header) + "'");
  if (rows == 0) throw InputError(path, "", "has a header but no data rows");
}

namespace {

// ForEachCsvRowByName's body; `on_other` hears the header's other columns with the header's
// "file:line".
void ForEachCsvRowByNameAt(std::istream& in, const std::string& path, char delimiter,
                           const std::vector<std::string>& required, const std::vector<std::string>& optional,
                           const std::function<void(const std::string&, const std::vector<std::string>&)>& on_other,
                           const std::function<void(const CsvRow&)>& on_row) {
  std::vector<std::string> wanted = required;
  wanted.insert(wanted.end(), optional.begin(), optional.end());
  bool have_header = false;
  std::size_t columns = 0;
  std::vector<std::size_t> index;  // file column of each wanted name (npos: an optional one absent)
  int rows = 0;
  CsvRow row;
  row.path = &path;
  row.header = &wanted;
  ForEachCsvLine(in, path, delimiter, [&](int line_no, const std::string& trimmed, std::vector<std::string>& cells) {
    const std::string where = path + ":" + std::to_string(line_no);
    if (!have_header) {
      // dl columns other than the robot's are another robot's file, never columns to ignore.
      const std::string other = OtherCableCount(required, cells);
      if (!other.empty()) throw InputError(where, "header", other + " (got '" + trimmed + "')");
      std::vector<std::string> missing, ignored;
      for (std::size_t k = 0; k < wanted.size(); ++k) {
        const std::string& name = wanted[k];
        const auto count = std::count(cells.begin(), cells.end(), name);
        if (count > 1) throw InputError(where, "header", "column '" + name + "' appears " + std::to_string(count) + " times");
        const bool is_required = k < required.size();
        if (count == 0 && is_required) missing.push_back(name);
        index.push_back(count == 0 ? std::string::npos
                                   : static_cast<std::size_t>(std::find(cells.begin(), cells.end(), name) - cells.begin()));
        row.present.push_back(count > 0);
      }
      for (const std::string& c : cells) {
        if (std::find(wanted.begin(), wanted.end(), c) == wanted.end()) ignored.push_back(c);
      }
      if (!missing.empty()) {
        const bool other_separator = cells.size() == 1 && delimiter == ',' && trimmed.find_first_of(";\t") != std::string::npos;
        throw InputError(where, "header",
                         "no column " + QuotedList(missing) + " (the columns needed are '" + JoinCsv(required) + "'" +
                             (optional.empty() ? std::string() : ", optionally '" + JoinCsv(optional) + "'") +
                             ", in any order; got '" + trimmed + "')" + CaseHint(missing, cells) +
                             (other_separator ? " (another separator? give it with --delimiter)" : ""));
      }
      if (!ignored.empty() && on_other) on_other(where, ignored);
      columns = cells.size();
      row.header_line = line_no;
      have_header = true;
      return;
    }
    if (cells.size() != columns) {
      throw InputError(where, "", "expected " + std::to_string(columns) + " cells (as the header), got " +
                                      std::to_string(cells.size()) + " (separator '" + std::string(1, delimiter) + "')");
    }
    row.line = line_no;
    row.cells.resize(wanted.size());
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      if (index[k] == std::string::npos) {
        row.cells[k].clear();
      } else {
        row.cells[k] = std::move(cells[index[k]]);
      }
    }
    on_row(row);
    ++rows;
  });
  if (!have_header) throw InputError(path, "", "is empty: no header line with '" + JoinCsv(required) + "'");
  if (rows == 0) throw InputError(path, "", "has a header but no data rows");
}

}  // namespace

void ForEachCsvRowByName(std::istream& in, const std::string& path, char delimiter,
                         const std::vector<std::string>& required, const std::vector<std::string>& optional,
                         const std::function<void(const std::vector<std::string>&)>& on_ignored,
                         const std::function<void(const CsvRow&)>& on_row) {
  ForEachCsvRowByNameAt(
      in, path, delimiter, required, optional,
      [&](const std::string&, const std::vector<std::string>& ignored) {
        if (on_ignored) on_ignored(ignored);
      },
      on_row);
}

void ForEachCsvRowByNameStrict(std::istream& in, const std::string& path, char delimiter,
                               const std::vector<std::string>& required, const std::vector<std::string>& optional,
                               const std::function<void(const CsvRow&)>& on_row,
                               const std::function<std::string(const std::vector<std::string>&)>& explain) {
  ForEachCsvRowByNameAt(
      in, path, delimiter, required, optional,
      [&](const std::string& where, const std::vector<std::string>& other) {
        throw InputError(where, "column '" + other.front() + "'",
                         "unknown column (the columns are '" + JoinCsv(required) + "'" +
                             (optional.empty() ? std::string() : ", optionally '" + JoinCsv(optional) + "'") + ")" +
                             (explain ? explain(other) : std::string()));
      },
      on_row);
}

}  // namespace cablecal
