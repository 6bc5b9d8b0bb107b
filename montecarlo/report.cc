// The files of a Monte Carlo study (errors.csv, failures.csv, summary.csv, summary.md): its
// statistics per cell and their one writer, apart from the study that fills the cells.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "common/format.h"
#include "montecarlo/montecarlo.h"

namespace cablecal {

std::vector<std::string> SummaryParameters(const std::vector<std::string>& geometry_names) {
  std::vector<std::string> names = geometry_names;
  names.push_back("x4");
  names.push_back("x_all");
  return names;
}

ErrorStats Summarise(const MonteCarloCell& cell, const std::vector<std::string>& geometry,
                     const std::string& parameter) {
  const int g = static_cast<int>(geometry.size());
  std::vector<double> e;
  for (const TrialOutcome& t : cell.trials) {
    if (!t.ok) continue;
    if (parameter == "x_all") {
      e.insert(e.end(), t.errors_m.begin() + g, t.errors_m.end());
    } else if (parameter == "x4") {
      if (cell.n >= 4) e.push_back(t.errors_m[g + 3]);
    } else {
      for (int k = 0; k < g; ++k) {
        if (parameter == geometry[k]) e.push_back(t.errors_m[k]);
      }
    }
  }
  // A pose a spatial trial skipped has no estimate (NaN): not an error to count.
  e.erase(std::remove_if(e.begin(), e.end(), [](double v) { return std::isnan(v); }), e.end());
  ErrorStats s;
  s.count = static_cast<int>(e.size());
  if (e.empty()) return s;
  double sum = 0, sum2 = 0;
  int within = 0;
  for (double v : e) {
    sum += v;
    sum2 += v * v;
    s.max_abs = std::max(s.max_abs, std::abs(v));
    within += std::abs(v) <= 0.005;
  }
  s.mean = sum / e.size();
  s.rms = std::sqrt(sum2 / e.size());
  double var = 0;
  for (double v : e) var += (v - s.mean) * (v - s.mean);
  s.std = e.size() > 1 ? std::sqrt(var / (e.size() - 1)) : 0.0;
  s.share_within_5mm = static_cast<double>(within) / e.size();
  return s;
}

std::string ErrorsCsv(const MonteCarloResult& r) {
  std::string out = "n,design,trial,parameter,error\n";
  const std::vector<std::string>& geometry = r.geometry_names;
  const std::size_t g = geometry.size();
  for (const MonteCarloCell& c : r.cells) {
    for (std::size_t t = 0; t < c.trials.size(); ++t) {
      const TrialOutcome& tr = c.trials[t];
      if (!tr.ok) continue;
      const std::string prefix = std::to_string(c.n) + "," + ToString(c.design) + "," + std::to_string(t + 1) + ",";
      for (std::size_t k = 0; k < tr.errors_m.size(); ++k) {
        if (std::isnan(tr.errors_m[k])) continue;  // a skipped pose (spatial --skip-infeasible)
        const std::string name = k < g ? geometry[k] : "x" + std::to_string(k - g + 1);
        out += prefix + name + "," + FormatDouble(tr.errors_m[k]) + "\n";
      }
    }
  }
  return out;
}

std::string FailuresCsv(const MonteCarloResult& r) {
  std::string out = "n,design,trial,cause,reason\n";
  for (const MonteCarloCell& c : r.cells) {
    for (std::size_t t = 0; t < c.trials.size(); ++t) {
      const TrialOutcome& tr = c.trials[t];
      if (tr.ok) continue;
      const std::size_t colon = tr.failure.find(':');
      const std::string cause = colon == std::string::npos ? "unknown" : tr.failure.substr(0, colon);
      std::string reason = colon == std::string::npos ? tr.failure : tr.failure.substr(colon + 1);
      if (!reason.empty() && reason[0] == ' ') reason.erase(0, 1);
      // RFC 4180 quoting: reasons contain commas.
      std::string quoted = "\"";
      for (const char ch : reason) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch == '\n' ? ' ' : ch);
      quoted += "\"";
      out += std::to_string(c.n) + "," + ToString(c.design) + "," + std::to_string(t + 1) + "," + cause + "," + quoted +
             "\n";
    }
  }
  return out;
}

std::string SummaryCsv(const MonteCarloResult& r) {
  std::string out = "n,design,parameter,mean,std,rms,max_abs,share_within_5mm,failures";
  for (const std::string& cause : FailureCauses()) out += ",failed_" + cause;
  out += "\n";
  for (const MonteCarloCell& c : r.cells) {
    for (const std::string& p : SummaryParameters(r.geometry_names)) {
      const ErrorStats s = Summarise(c, r.geometry_names, p);
      // No successful trial: no statistic (empty cells), never a zero; one trial: no std (x_all
      // pools a trial's poses, whose spread within one trial is not the spread over trials).
      const int successes = static_cast<int>(c.trials.size()) - c.failures();
      auto stat = [&](double v, int needed) {
        return s.count >= needed && successes >= needed ? FormatDouble(v) : std::string();
      };
      out += std::to_string(c.n) + "," + ToString(c.design) + "," + p + "," + stat(s.mean, 1) + "," + stat(s.std, 2) +
             "," + stat(s.rms, 1) + "," + stat(s.max_abs, 1) + "," + stat(s.share_within_5mm, 1) + "," +
             std::to_string(c.failures());
      for (const std::string& cause : FailureCauses()) out += "," + std::to_string(c.failures(cause));
      out += "\n";
    }
  }
  return out;
}

std::string SummaryMarkdown(const MonteCarloResult& r, const std::string& title) {
  std::ostringstream o;
  o << "# " << PrintableText(title) << "\n\n";  // a robot name with a newline must not end the heading
  o << "Standard deviation of the identification error (identified - true) in mm, per pose count n\n"
       "and pose-set design; `x4` is the 4th pose's x, `x_all` every pose's x pooled. `failed` counts\n"
       "trials that failed, by cause: design (no verified pose set), sampling, simulation (the true robot cannot\n"
       "hold a commanded pose within its limits), identification. Failed trials have no error to count, so the\n"
       "statistics are over the successful ones: compare designs on both columns.\n\n";
  o << "| n | design |";
  for (const std::string& p : SummaryParameters(r.geometry_names)) o << " " << p << " |";
  o << " within ±5 mm | failed |\n|---|---|";
  for (std::size_t k = 0; k < SummaryParameters(r.geometry_names).size() + 2; ++k) o << "---|";
  o << "\n";
  char buf[32];
  for (const MonteCarloCell& c : r.cells) {
    o << "| " << c.n << " | " << ToString(c.design) << " |";
    int within = 0, count = 0;
    // Fewer than two successful trials: n/a everywhere (README), x_all too, whose poses pooled
    // from one trial would read as a spread over trials (a new user's trial: 0.76 mm from one).
    const bool spread = static_cast<int>(c.trials.size()) - c.failures() > 1;
    for (const std::string& p : SummaryParameters(r.geometry_names)) {
      const ErrorStats s = Summarise(c, r.geometry_names, p);
      if (spread && s.count > 1) {
        std::snprintf(buf, sizeof(buf), " %.3f |", 1e3 * s.std);
        o << buf;
      } else {
        o << " n/a |";  // no successful trial: no statistic, not zero
      }
      if (p != "x_all" && p != "x4") {
        within += static_cast<int>(std::lround(s.share_within_5mm * s.count));
        count += s.count;
      }
    }
    const ErrorStats xs = Summarise(c, r.geometry_names, "x_all");
    within += static_cast<int>(std::lround(xs.share_within_5mm * xs.count));
    count += xs.count;
    if (spread) {
      std::snprintf(buf, sizeof(buf), " %.1f %% |", count ? 100.0 * within / count : 0.0);
    } else {
      std::snprintf(buf, sizeof(buf), " n/a |");
    }
    o << buf << " " << c.failures() << " / " << c.trials.size();
    std::string causes;
    for (const std::string& cause : FailureCauses()) {
      if (c.failures(cause) > 0) causes += (causes.empty() ? "" : ", ") + cause + " " + std::to_string(c.failures(cause));
    }
    if (!causes.empty()) o << " (" << causes << ")";
    o << " |\n";
  }
  long skipped = 0, held = 0;
  for (const MonteCarloCell& c : r.cells) {
    for (const TrialOutcome& t : c.trials) {
      skipped += t.skipped_poses;
      if (t.ok) held += c.n - t.skipped_poses;
    }
  }
  if (skipped > 0) {
    o << "\nThe trials skipped " << skipped << " poses their true robot could not hold within its limits "
      << "(--skip-infeasible); the successful ones identified from " << held << " poses.\n";
  }
  // Before measuring, the lab knew every parameter to geometry_sigma_m (the true geometry is
  // drawn so): a calibration that knows less, or hardly more, is said to be one.
  const std::vector<std::string> worse = CellsThatAddLittle(r, true), little = CellsThatAddLittle(r, false);
  if (r.geometry_sigma_m > 0.0 && !little.empty()) {
    std::snprintf(buf, sizeof(buf), "%.3g mm", 1e3 * r.geometry_sigma_m);
    o << "\nBefore measuring, every geometric parameter was known to " << buf
      << " (the true geometry is drawn so). ";
    if (!worse.empty()) {
      o << "In these cells the calibration knows some parameters **less** well than that:\n\n";
      for (const std::string& c : worse) o << "- " << c << "\n";
      o << "\n";
    }
    if (little.size() > worse.size()) {
      o << "In these cells the measurements add little to it (a sigma above "
        << FormatDouble(kDataAddLittle) << " x that" << (worse.empty() ? "" : ", the cells above included") << "):\n\n";
      for (const std::string& c : little) o << "- " << c << "\n";
      o << "\n";
    }
    if (r.geometry_prior) {
      o << "The trials were identified with that knowledge as a prior (--geometry-prior).\n";
    } else if (r.geometry_prior_served) {
      o << "Identify with that knowledge as a prior (--geometry-prior) so that a calibration never knows less than "
           "the lab did.\n";
    } else {
      o << "A calibration that must never know less than the lab did takes that knowledge as a prior (identify "
           "--gauge prior, with the robot file's tracker sigma); the Monte Carlo does not yet simulate it for "
           "spatial robots.\n";
    }
  }
  return o.str();
}

std::vector<std::string> CellsThatAddLittle(const MonteCarloResult& r, bool worse) {
  std::vector<std::string> out;
  if (!(r.geometry_sigma_m > 0.0)) return out;
  const double bound = worse ? r.geometry_sigma_m : kDataAddLittle * r.geometry_sigma_m;
  const std::vector<std::string>& names = r.geometry_names;
  for (const MonteCarloCell& c : r.cells) {
    std::vector<std::pair<double, std::string>> over;
    for (std::size_t k = 0; k < names.size(); ++k) {
      // The held coordinates define the frame: not estimates.
      if (std::find(r.held_names.begin(), r.held_names.end(), names[k]) != r.held_names.end()) continue;
      const ErrorStats s = Summarise(c, r.geometry_names, names[k]);
      if (s.count > 1 && s.std > bound) over.emplace_back(s.std, names[k]);
    }
    if (over.empty()) continue;
    std::stable_sort(over.begin(), over.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::string text = "n=" + std::to_string(c.n) + " " + ToString(c.design) + ":";
    char buf[48];
    for (std::size_t k = 0; k < over.size() && k < 4; ++k) {
      std::snprintf(buf, sizeof(buf), "%s %s %.3g mm", k ? "," : "", over[k].second.c_str(), 1e3 * over[k].first);
      text += buf;
    }
    if (over.size() > 4) text += ", ...";
    out.push_back(text);
  }
  return out;
}

std::string DesignComparisonMarkdown(const MonteCarloResult& r, PoseSetDesign design) {
  std::vector<std::string> free;
  for (const std::string& g : r.geometry_names) {
    if (std::find(r.held_names.begin(), r.held_names.end(), g) == r.held_names.end()) free.push_back(g);
  }
  const auto successful = [](const MonteCarloCell& c) { return static_cast<int>(c.trials.size()) - c.failures(); };
  std::ostringstream o;
  o << "| n | " << ToString(design) << " against | smaller sigma | median ratio | largest ratio | failed ("
    << ToString(design) << " / other) | holds |\n|---|---|---|---|---|---|---|\n";
  char buf[160];
  for (const MonteCarloCell& mine : r.cells) {
    if (mine.design != design) continue;
    for (const MonteCarloCell& other : r.cells) {
      if (other.n != mine.n || other.design == design) continue;
      o << "| " << mine.n << " | " << ToString(other.design) << " | ";
      const std::string failed = std::to_string(mine.failures()) + " / " + std::to_string(other.failures());
      if (successful(mine) < 2 || successful(other) < 2 || free.empty()) {
        o << "n/a | n/a | n/a | " << failed << " | n/a |\n";
        continue;
      }
      std::vector<double> ratios;
      int smaller = 0;
      std::string worst;
      double worst_ratio = -1.0;
      for (const std::string& p : free) {
        const double ratio = Summarise(mine, r.geometry_names, p).std / Summarise(other, r.geometry_names, p).std;
        ratios.push_back(ratio);
        smaller += ratio < 1.0;
        if (ratio > worst_ratio) {
          worst_ratio = ratio;
          worst = p;
        }
      }
      std::sort(ratios.begin(), ratios.end());
      const std::size_t k = ratios.size();
      const double median = k % 2 ? ratios[k / 2] : 0.5 * (ratios[k / 2 - 1] + ratios[k / 2]);
      const double slack = kComparisonFailureSlack * static_cast<double>(mine.trials.size());
      const bool holds = smaller == static_cast<int>(k) && mine.failures() <= other.failures() + slack;
      std::snprintf(buf, sizeof(buf), "%d of %zu | %.3f | %.3f (%s) | %s | %s |\n", smaller, k, median, worst_ratio,
                    worst.c_str(), failed.c_str(), holds ? "yes" : "no");
      o << buf;
    }
  }
  return o.str();
}

}  // namespace cablecal
