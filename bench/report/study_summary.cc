#include "bench/report/study_summary.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <regex>
#include <set>

namespace twin {
namespace {

using json = nlohmann::json;

json Num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json StatsJson(const FigureStats& s) {
  return json{{"n", s.n},           {"mean", Num(s.mean)}, {"std", Num(s.std)},
              {"median", Num(s.median)}, {"p5", Num(s.p5)}, {"p95", Num(s.p95)},
              {"min", Num(s.min)},  {"max", Num(s.max)},
              {"ci95_mean", {Num(s.ci95_low), Num(s.ci95_high)}}};
}

bool Number(const json& j, double* v) {
  if (j.is_boolean()) {
    *v = j.get<bool>() ? 1.0 : 0.0;
    return true;
  }
  if (!j.is_number()) return false;
  *v = j.get<double>();
  return std::isfinite(*v);
}

const json* Field(const json& figures, const std::string& key) {
  const auto it = figures.find(key);
  return it == figures.end() ? nullptr : &*it;
}

}  // namespace

double Quantile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double h = (sorted.size() - 1) * std::clamp(p, 0.0, 1.0);
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(sorted.size() - 1, lo + 1);
  return sorted[lo] + (h - lo) * (sorted[hi] - sorted[lo]);
}

double StudentT975(int dof) {
  // Exact table for small dof, then the Cornish-Fisher expansion about z = 1.959964 (error
  // below 1e-4 from dof 30 on).
  static const double kTable[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                                  2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                                  2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                                  2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) return std::numeric_limits<double>::quiet_NaN();
  if (dof <= 30) return kTable[dof - 1];
  const double z = 1.959964, n = dof;
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4 * n) + (5 * z5 + 16 * z3 + 3 * z) / (96 * n * n) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * n * n * n);
}

void WilsonInterval95(int k, int n, double* low, double* high) {
  if (n <= 0) {
    *low = *high = std::numeric_limits<double>::quiet_NaN();
    return;
  }
  const double z = 1.959964, p = static_cast<double>(k) / n;
  const double d = 1 + z * z / n;
  const double c = (p + z * z / (2 * n)) / d;
  const double h = z * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n)) / d;
  *low = std::max(0.0, c - h);
  *high = std::min(1.0, c + h);
}

FigureStats ComputeFigureStats(std::vector<double> v) {
  FigureStats s;
  s.n = static_cast<int>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / s.n;
  double ss = 0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = s.n > 1 ? std::sqrt(ss / (s.n - 1)) : 0.0;
  s.median = Quantile(v, 0.5);
  s.p5 = Quantile(v, 0.05);
  s.p95 = Quantile(v, 0.95);
  s.min = v.front();
  s.max = v.back();
  if (s.n > 1) {
    const double half = StudentT975(s.n - 1) * s.std / std::sqrt(static_cast<double>(s.n));
    s.ci95_low = s.mean - half;
    s.ci95_high = s.mean + half;
  } else {
    s.ci95_low = s.ci95_high = std::numeric_limits<double>::quiet_NaN();
  }
  return s;
}

json SummarizeStudy(const std::vector<json>& records) {
  json out;
  std::set<std::string> names, hashes;
  std::vector<const json*> ok;
  json failures = json::array();
  int first = -1, last = -1;
  std::vector<const json*> sorted;
  for (const json& r : records) sorted.push_back(&r);
  std::sort(sorted.begin(), sorted.end(), [](const json* a, const json* b) {
    return a->value("trial", 0) < b->value("trial", 0);
  });
  for (const json* r : sorted) {
    names.insert(r->value("scenario", std::string()));
    hashes.insert(r->value("scenario_hash", std::string()));
    const int t = r->value("trial", 0);
    first = first < 0 ? t : std::min(first, t);
    last = std::max(last, t);
    if (r->value("status", std::string()) == "ok") {
      ok.push_back(r);
    } else {
      failures.push_back({{"trial", t}, {"reason", r->value("reason", std::string())}});
    }
  }
  out["scenario"] = {{"names", names}, {"hashes", hashes}};
  // The GL back ends the trials rendered with (report timing_s.cell.renderer, kept among the
  // record's timings): trials drawn by two rasterisers are not one distribution of figures.
  json renderers = json::object();
  for (const json* r : sorted) {
    const auto run = r->find("run");
    if (run == r->end() || !run->is_object() || !run->contains("timing")) continue;
    const json& timing = (*run)["timing"];
    const auto name = timing.find("timing_s.cell.renderer");
    if (name == timing.end() || !name->is_string()) continue;
    const std::string key = name->get<std::string>();
    renderers[key] = renderers.value(key, 0) + 1;
  }
  out["renderers"] = renderers;
  out["trials"] = {{"recorded", records.size()},
                   {"ok", ok.size()},
                   {"failed", failures.size()},
                   {"first", first},
                   {"last", last},
                   {"failures", failures}};

  // Every figure over the ok trials.
  std::map<std::string, std::vector<double>> values;
  for (const json* r : ok) {
    const auto f = r->find("figures");
    if (f == r->end() || !f->is_object()) continue;
    for (const auto& [key, value] : f->items()) {
      double v;
      if (Number(value, &v)) values[key].push_back(v);
    }
  }
  json figures = json::object();
  for (const auto& [key, v] : values) figures[key] = StatsJson(ComputeFigureStats(v));
  out["figures"] = figures;

  // Per-parameter errors and the coverage check.
  static const std::regex kParam(R"(^(robots\.[^.\[]+)\.parameters\[([^\]]+)\]\.estimated$)");
  static const std::regex kCombo(
      R"(^(robots\.[^.\[]+)\.identifiable_combinations\.items\[(\d+)\]\.estimated$)");
  static const std::regex kEffect(R"(^discovery\.effects\[([^\]]+)\]\.present$)");
  std::map<std::string, std::map<std::string, std::vector<double>>> param_errors;
  std::map<std::string, std::string> param_units;
  struct Cover {
    int n = 0, in1 = 0, in2 = 0;
    double sum_sq = 0;
  };
  std::map<std::string, std::map<int, Cover>> cover;
  struct Detect {
    int named = 0, missed = 0, false_named = 0, trials = 0;
  };
  std::map<std::string, Detect> detect;
  for (const json* r : ok) {
    const auto fi = r->find("figures");
    if (fi == r->end() || !fi->is_object()) continue;
    const json& f = *fi;
    const json* labels = r->contains("labels") ? &(*r)["labels"] : nullptr;
    for (const auto& [key, value] : f.items()) {
      std::smatch m;
      double est, tru, sig;
      if (std::regex_match(key, m, kParam)) {
        const std::string base = key.substr(0, key.size() - std::string("estimated").size());
        const json* t = Field(f, base + "true");
        if (t && Number(value, &est) && Number(*t, &tru)) {
          param_errors[m[1]][m[2]].push_back(est - tru);
          if (labels && labels->contains(base + "unit")) {
            param_units[std::string(m[1]) + "|" + std::string(m[2])] = (*labels)[base + "unit"];
          }
        }
      } else if (std::regex_match(key, m, kCombo)) {
        const std::string base = key.substr(0, key.size() - std::string("estimated").size());
        const json* t = Field(f, base + "true");
        const json* s = Field(f, base + "sigma");
        if (t && s && Number(value, &est) && Number(*t, &tru) && Number(*s, &sig) && sig > 0) {
          Cover& c = cover[m[1]][std::stoi(m[2])];
          const double e = std::abs(est - tru) / sig;
          ++c.n;
          c.in1 += e <= 1.0;
          c.in2 += e <= 2.0;
          c.sum_sq += e * e;
        }
      } else if (std::regex_match(key, m, kEffect)) {
        const std::string effect = m[1];
        const json* named = Field(f, "discovery.effects[" + effect + "].named");
        if (!named || !value.is_boolean() || !named->is_boolean()) continue;
        Detect& d = detect[effect];
        ++d.trials;
        const bool p = value.get<bool>(), nm = named->get<bool>();
        d.named += p && nm;
        d.missed += p && !nm;
        d.false_named += !p && nm;
      }
    }
  }
  json pe = json::object();
  for (const auto& [robot, params] : param_errors) {
    for (const auto& [name, v] : params) {
      json s = StatsJson(ComputeFigureStats(v));
      double ss = 0;
      for (double x : v) ss += x * x;
      s["rms"] = std::sqrt(ss / v.size());
      const auto u = param_units.find(robot + "|" + name);
      s["unit"] = u == param_units.end() ? "" : u->second;
      pe[robot][name] = s;
    }
  }
  out["parameter_errors"] = pe;
  json cov = json::object();
  for (const auto& [robot, items] : cover) {
    json list = json::array();
    Cover all;
    for (const auto& [index, c] : items) {
      list.push_back({{"index", index},
                      {"n", c.n},
                      {"within_1_sigma", static_cast<double>(c.in1) / c.n},
                      {"within_2_sigma", static_cast<double>(c.in2) / c.n},
                      {"rms_normalized_error", std::sqrt(c.sum_sq / c.n)}});
      all.n += c.n;
      all.in1 += c.in1;
      all.in2 += c.in2;
      all.sum_sq += c.sum_sq;
    }
    double l1, h1, l2, h2;
    WilsonInterval95(all.in1, all.n, &l1, &h1);
    WilsonInterval95(all.in2, all.n, &l2, &h2);
    cov[robot] = {{"combinations", list},
                  {"pooled",
                   {{"n", all.n},
                    {"within_1_sigma", all.n ? static_cast<double>(all.in1) / all.n : 0.0},
                    {"within_2_sigma", all.n ? static_cast<double>(all.in2) / all.n : 0.0},
                    {"within_1_sigma_interval95", {Num(l1), Num(h1)}},
                    {"within_2_sigma_interval95", {Num(l2), Num(h2)}},
                    {"rms_normalized_error", all.n ? std::sqrt(all.sum_sq / all.n) : 0.0}}},
                  {"expected", {{"within_1_sigma", 0.683}, {"within_2_sigma", 0.954}}}};
  }
  out["coverage"] = cov;
  if (!detect.empty()) {
    json d = json::object();
    for (const auto& [effect, c] : detect) {
      d[effect] = {{"trials", c.trials}, {"named", c.named}, {"missed", c.missed},
                   {"false", c.false_named}};
    }
    out["detection"] = d;
  }
  return out;
}

}  // namespace twin
