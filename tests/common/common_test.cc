#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <clocale>

#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <set>

#include "common/parallel.h"
#include "tests/support/temp_dir.h"
#include "common/atomic_output.h"
#include "common/csv.h"
#include "common/error.h"
#include "common/format.h"
#include "common/json.h"
#include "common/yaml_writer.h"
#include "common/random.h"

namespace cablecal {
namespace {

namespace fs = std::filesystem;


TEST(Format, ShortestRoundTrip) {
  for (const double v : {0.1, 2.6045, 1.0 / 3.0, -5.209e-7, 1e300, 123456789.0}) {
    double back = 0.0;
    ASSERT_TRUE(ParseFiniteDouble(FormatDouble(v), &back)) << FormatDouble(v);
    EXPECT_EQ(back, v);
  }
  EXPECT_EQ(FormatDouble(2.6045), "2.6045");
  EXPECT_EQ(FormatDouble(-0.0), "0");
}

// Messages quote file contents: control characters and bytes that are not UTF-8 are escaped,
// UTF-8 characters (a lab's names, a sigma) pass whole.
TEST(Format, PrintableTextEscapesControlsAndInvalidUtf8) {
  EXPECT_EQ(PrintableText("a\tb\n"), "a\\tb\\n");
  EXPECT_EQ(PrintableText("\x1b[31m"), "\\x1b[31m");
  EXPECT_EQ(PrintableText("\xcf\x83 = 1 mm, M\xc3\xbcller, \xe2\x82\xac, \xf0\x9f\x99\x82"),
            "\xcf\x83 = 1 mm, M\xc3\xbcller, \xe2\x82\xac, \xf0\x9f\x99\x82");
  EXPECT_EQ(PrintableText("\xff\xfe"), "\\xff\\xfe");            // not UTF-8 at all
  EXPECT_EQ(PrintableText("\xc3("), "\\xc3(");                    // a lead byte without its continuation
  EXPECT_EQ(PrintableText("\xc0\xaf"), "\\xc0\\xaf");          // overlong
  EXPECT_EQ(PrintableText("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // a surrogate
  EXPECT_EQ(PrintableText("\xe2\x82"), "\\xe2\\x82");          // cut short at the end
}

TEST(Format, ParseRejectsNonFinite) {
  double v = 0.0;
  for (const char* bad : {"", "nan", "NaN", "inf", "-inf", "1e400", "1.0x", " 1", "0x"}) {
    EXPECT_FALSE(ParseFiniteDouble(bad, &v)) << bad;
  }
  EXPECT_TRUE(ParseFiniteDouble("1e-400", &v));  // underflow to zero is a number
  EXPECT_TRUE(ParseFiniteDouble("-2.5e3", &v));
  EXPECT_EQ(v, -2500.0);
}

TEST(Format, YamlReadersSeeFloats) {
  // PyYAML (YAML 1.1) reads "1e-05" as a string; every number written has a '.' before 'e'.
  EXPECT_EQ(FormatDouble(1e-5), "1.0e-05");
  EXPECT_EQ(FormatDouble(2.5e-7), "2.5e-07");
  EXPECT_EQ(FormatDouble(1e22), "1.0e+22");
  for (const double v : {1e-5, 3e300, -7e-12}) {
    double back = 0.0;
    ASSERT_TRUE(ParseFiniteDouble(FormatDouble(v), &back));
    EXPECT_EQ(back, v);
  }
  double v = 0.0;
  EXPECT_TRUE(ParseFiniteDouble("+1.5", &v));
  EXPECT_EQ(v, 1.5);
  EXPECT_FALSE(ParseFiniteDouble("+-1", &v));
  EXPECT_FALSE(ParseFiniteDouble("1,5", &v));
  EXPECT_TRUE(ParseFiniteDouble("1e-400", &v));
  EXPECT_EQ(v, 0.0);
}

// FlowRows, the writer of long tables (issue 24), writes byte for byte what yaml-cpp's emitter
// writes for the same block sequence of flow maps, and as JSON what ToJson makes of that YAML:
// random rows of integers, numbers of every size and sign, NaN and infinities, lists of 0 to 3
// numbers; tables of 0, 1 and 40 rows; with and without a comment.
TEST(FlowRows, SameTextAsTheEmitterAndTheSameJsonAsToJson) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> specials = {0.0, -0.0, 1.0, 3.0, -2.5e-7, 1e22, 1e-5, std::nan(""), inf, -inf, 0.1,
                                        123456789.0};
  Rng rng(24);
  const auto number = [&]() {
    if (rng.Uniform() < 0.3) return specials[static_cast<std::size_t>(rng.Uniform() * specials.size())];
    const double mantissa = rng.Normal();  // sequenced: the operands of * are not
    return mantissa * std::pow(10.0, std::floor(rng.Uniform(-12.0, 12.0)));
  };
  for (const int rows : {0, 1, 40}) {
    for (const std::string comment : {"", "per reading (data row), model - reading; 1 = full"}) {
      YAML::Emitter head, whole;
      head << YAML::BeginMap << YAML::Key << "head" << YAML::Value << YamlString{std::string("a: b")} << YAML::EndMap;
      whole << YAML::BeginMap << YAML::Key << "head" << YAML::Value << YamlString{std::string("a: b")} << YAML::Key
            << "table" << YAML::Value;
      if (!comment.empty()) whole << YAML::Comment(comment);
      whole << YAML::BeginSeq;
      FlowRows yaml(FlowRows::Syntax::kYaml), json(FlowRows::Syntax::kJson);
      for (int r = 0; r < rows; ++r) {
        const long long id = static_cast<long long>(rng.Uniform(-1e6, 1e12));
        const double x = number(), y = number();
        std::vector<double> list(static_cast<std::size_t>(rng.Uniform() * 4.0));
        for (double& v : list) v = number();
        whole << YAML::Flow << YAML::BeginMap << YAML::Key << "pose" << YAML::Value << id << YAML::Key << "x"
              << YAML::Value << YamlNumber{x} << YAML::Key << "encoder_sigmas" << YAML::Value << YAML::Flow
              << YAML::BeginSeq;
        for (const double v : list) whole << YamlNumber{v};
        whole << YAML::EndSeq << YAML::Key << "y_2" << YAML::Value << YamlNumber{y} << YAML::EndMap;
        for (FlowRows* t : {&yaml, &json}) {
          t->BeginRow();
          t->Key("pose");
          t->Int(id);
          t->Key("x");
          t->Number(x);
          t->Key("encoder_sigmas");
          t->BeginList();
          for (const double v : list) t->Number(v);
          t->EndList();
          t->Key("y_2");
          t->Number(y);
          t->EndRow();
        }
      }
      whole << YAML::EndSeq << YAML::EndMap;
      const std::string expected = YamlText(whole);
      EXPECT_EQ(YamlText(head) + yaml.Finish("table", comment), expected) << rows << " rows";
      EXPECT_EQ(MergeJsonObjects({ToJson(YAML::Load(YamlText(head))), json.Finish("table")}),
                ToJson(YAML::Load(expected)))
          << rows << " rows";
    }
  }
}

TEST(Format, ParsingIgnoresADecimalCommaLocale) {
  // A process whose C locale writes decimal commas (a library user's) reads the same.
  double v = 0.0;
  const char* old = std::setlocale(LC_NUMERIC, nullptr);
  const std::string saved = old ? old : "C";
  bool switched = false;
  for (const char* name : {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "C.UTF-8"}) {
    if (std::setlocale(LC_NUMERIC, name) && std::string(std::localeconv()->decimal_point) == ",") {
      switched = true;
      break;
    }
  }
  EXPECT_TRUE(ParseFiniteDouble("2.75", &v));
  EXPECT_EQ(v, 2.75);
  std::setlocale(LC_NUMERIC, saved.c_str());
  if (!switched) GTEST_SKIP() << "no locale with a decimal comma is installed here";
}

TEST(Random, SameSeedSameStreamAndStreamsDiffer) {
  Rng a(42), b(42), c(43);
  int same_as_other_seed = 0;
  for (int i = 0; i < 100; ++i) {
    const double x = a.Normal();
    EXPECT_EQ(x, b.Normal());
    same_as_other_seed += x == c.Normal();
  }
  EXPECT_EQ(same_as_other_seed, 0);  // another seed gives another stream
  std::set<std::uint64_t> seeds;
  for (std::uint64_t n = 0; n < 50; ++n) {
    for (std::uint64_t t = 0; t < 50; ++t) seeds.insert(StreamSeed(1, {n, t}));
  }
  EXPECT_EQ(seeds.size(), 2500u);
}

TEST(Random, NormalHasUnitMoments) {
  Rng rng(9);
  const int n = 200000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = rng.Normal();
    sum += x;
    sum2 += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 5.0 / std::sqrt(n));           // 5 standard errors
  EXPECT_NEAR(sum2 / n, 1.0, 5.0 * std::sqrt(2.0 / n));
}

TEST(AtomicOutput, NothingAppearsWithoutCommit) {
  const testing_support::TempDir tmp;
  const fs::path dir = tmp.path();
  const std::string final_path = (dir / "out.csv").string();
  {
    AtomicOutput out;
    const std::string temp = out.WriteText(final_path, "a,b\n");
    EXPECT_TRUE(fs::exists(temp));
    EXPECT_FALSE(fs::exists(final_path));
  }
  EXPECT_FALSE(fs::exists(final_path));
  EXPECT_TRUE(fs::is_empty(dir));
  {
    AtomicOutput out;
    out.WriteText(final_path, "a,b\n");
    out.Commit();
  }
  EXPECT_TRUE(fs::exists(final_path));
}

TEST(AtomicOutput, MissingFolderIsInputError) {
  AtomicOutput out;
  EXPECT_THROW(out.WriteText("/nonexistent-folder/x.csv", "x"), InputError);
}

// Before any work: an output under a regular file says so (not "does not exist"), and a folder
// that takes no new files is refused naming the flag. Root may write anywhere, so the
// permission case runs as another user only.
TEST(AtomicOutput, OutputsThatCannotBeWrittenAreRefusedBeforeTheWork) {
  const testing_support::TempDir tmp;
  const std::string file = (tmp.path() / "afile").string();
  std::ofstream(file) << "x";
  const auto message = [](const std::string& path) {
    try {
      CheckCommandPaths({}, {PathArgument{"--out", path}});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string under_file = message(file + "/x.csv");
  EXPECT_NE(under_file.find("--out"), std::string::npos) << under_file;
  EXPECT_NE(under_file.find("'" + file + "' is a file, not a folder"), std::string::npos) << under_file;
  const std::string deeper = message(file + "/x/y.csv");  // its first existing ancestor is the file
  EXPECT_NE(deeper.find("'" + file + "' is a file, not a folder"), std::string::npos) << deeper;
  const std::string missing = message((tmp.path() / "nowhere" / "x.csv").string());
  EXPECT_NE(missing.find("folder '" + (tmp.path() / "nowhere").string() + "' does not exist"), std::string::npos)
      << missing;
  EXPECT_EQ(message((tmp.path() / "x.csv").string()), "");
  const fs::path locked = tmp.path() / "locked";
  fs::create_directory(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                              fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
  const std::string path = (locked / "x.csv").string();
  if (::geteuid() != 0) {
    EXPECT_NE(message(path).find("no permission to create files in folder"), std::string::npos) << message(path);
    return;
  }
  // Root writes into any folder: the check runs as nobody in a child process.
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const bool nobody = ::setgid(65534) == 0 && ::setuid(65534) == 0;
    ::_exit(!nobody ? 2 : message(path).find("no permission to create files in folder") != std::string::npos ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the locked folder was not refused; 2: could not become nobody";
}

TEST(Csv, ToleratesBomCrlfCommentsAndSpaces) {
  const testing_support::TempDir tmp;
  const fs::path dir = tmp.path();
  const std::string path = (dir / "in.csv").string();
  std::ofstream(path, std::ios::binary) << "\xEF\xBB\xBF# made by hand\r\npose, x\r\n\r\n 1 , 2.5 \r\n# note\r\n2,3\r\n";
  std::vector<double> xs;
  ForEachCsvRow(path, {"pose", "x"}, [&](const CsvRow& row) {
    EXPECT_GT(row.PositiveInt(0), 0);
    xs.push_back(row.Number(1));
  });
  EXPECT_EQ(xs, (std::vector<double>{2.5, 3.0}));
}

TEST(Csv, ErrorsNameFileLineAndColumn) {
  const testing_support::TempDir tmp;
  const fs::path dir = tmp.path();
  const std::string path = (dir / "in.csv").string();
  auto message = [&](const std::string& content) -> std::string {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
    try {
      ForEachCsvRow(path, {"pose", "x"}, [](const CsvRow& row) { row.Number(1); row.PositiveInt(0); });
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(message("pose,x\n1,nan\n"), path + ":2: column 'x': must be a finite number (got 'nan')");
  EXPECT_EQ(message("pose,x\n1,1e400\n"), path + ":2: column 'x': must be a finite number (got '1e400')");
  EXPECT_EQ(message("pose,y\n1,2\n"), path + ":1: header: expected 'pose,x', got 'pose,y' ('x' missing)");
  // A dropped column is named (helper-23: a plan with one column dropped was told only the headers).
  EXPECT_EQ(message("pose\n1\n"), path + ":1: header: expected 'pose,x', got 'pose' ('x' missing)");
  EXPECT_EQ(message("pose,x,z\n1,2,3\n"), path + ":1: header: expected 'pose,x', got 'pose,x,z'");
  EXPECT_EQ(message("pose,x\n1,2,3\n"), path + ":2: expected 2 columns, got 3");
  EXPECT_EQ(message("pose,x\n0,2\n"), path + ":2: column 'pose': must be a positive integer (got '0')");
  // Positive but too long for an id is said so (helper-24: "must be a positive integer" of 10^20);
  // leading zeros do not count toward its nine digits.
  EXPECT_EQ(message("pose,x\n99999999999999999999,2\n"),
            path + ":2: column 'pose': must be a positive integer of at most 9 digits (got '99999999999999999999')");
  EXPECT_EQ(message("pose,x\n0000000000007,2\n"), "");
  EXPECT_EQ(message(""), path + ": is empty: no header line 'pose,x'");
  EXPECT_EQ(message("pose,x\n"), path + ": has a header but no data rows");
  EXPECT_EQ(message("pose,x\n1,2\n" + std::string(kMaxCsvLineBytes + 5, '#') + "\n3,4\n"),
            path + ":3: a line longer than " + std::to_string(kMaxCsvLineBytes) + " bytes: is this a CSV file?");
  EXPECT_EQ(message("pose,x\n1,2\n2,3"), "");  // a last line without its newline is a row
  // A line of exactly the limit is still read.
  EXPECT_EQ(message("pose,x\n#" + std::string(kMaxCsvLineBytes - 1, ' ') + "\n1,2\n"), "");
}

TEST(Csv, AnEndlessInputWithoutNewlinesIsRefusedAtTheLineLimit) {
  try {
    ForEachCsvRow("/dev/zero", {"pose", "x"}, [](const CsvRow&) {});
    FAIL() << "/dev/zero read as a CSV";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/dev/zero:1: a line longer than " + std::to_string(kMaxCsvLineBytes) +
                                         " bytes: is this a CSV file?");
  }
}


// An exception inside the parallel loop reaches the caller (not std::terminate), and the
// loop stops taking new iterations.
TEST(ParallelFor, AnExceptionInTheLoopIsRethrownAfterIt) {
  std::atomic<long> ran{0};
  EXPECT_THROW(ParallelFor(100000, 1,
                           [&](long k) {
                             ++ran;
                             if (k == 10) throw std::bad_alloc();
                           }),
               std::bad_alloc);
  EXPECT_LT(ran.load(), 100000);
  long sum = 0;
  std::vector<long> seen(1000, 0);
  ParallelFor(1000, 7, [&](long k) { seen[k] = k; });
  for (long v : seen) sum += v;
  EXPECT_EQ(sum, 999 * 1000 / 2);
}

}  // namespace
}  // namespace cablecal
