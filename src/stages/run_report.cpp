#include "stages/run_report.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace probelight {

double SampleSeries::percentile(double p) const {
  if (values_.empty()) return 0.0;
  std::vector<double> sorted = values_;
  std::sort(sorted.begin(), sorted.end());
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(sorted.size()));
  const size_t index = rank < 1.0 ? 0 : static_cast<size_t>(rank) - 1;
  return sorted[std::min(index, sorted.size() - 1)];
}

double SampleSeries::max() const {
  return values_.empty() ? 0.0 : *std::max_element(values_.begin(), values_.end());
}

double SampleSeries::mean() const {
  return values_.empty() ? 0.0 : std::accumulate(values_.begin(), values_.end(), 0.0) / static_cast<double>(values_.size());
}

void RunReport::recordStageSkip(const std::string& stage, const std::string& reason) {
  ++stage_skips_[stage];
  ++stage_skip_reasons_[stage][reason];
}

const SampleSeries* RunReport::stage(const std::string& name) const {
  auto it = stage_ms_.find(name);
  return it == stage_ms_.end() ? nullptr : &it->second;
}

const SampleSeries* RunReport::accuracy(const std::string& name) const {
  auto it = accuracy_.find(name);
  return it == accuracy_.end() ? nullptr : &it->second;
}

long long RunReport::counter(const std::string& name) const {
  auto it = counters_.find(name);
  return it == counters_.end() ? 0 : it->second;
}

nlohmann::json RunReport::toJson(long long frames, double elapsed_s) const {
  nlohmann::json out;
  out["frames"] = frames;
  out["fps"] = finiteOrNull(elapsed_s > 0.0 ? static_cast<double>(frames) / elapsed_s : 0.0);
  out["elapsed_s"] = finiteOrNull(elapsed_s);
  // The median interval between shown frames, and the rate it gives: what
  // the pipeline sustains once running.
  if (!frame_interval_ms_.empty()) {
    out["frame_interval_ms"] = {{"median", finiteOrNull(frame_interval_ms_.median())},
                                {"p95", finiteOrNull(frame_interval_ms_.percentile(95.0))}};
    out["fps_steady"] = finiteOrNull(frame_interval_ms_.median() > 0.0 ? 1e3 / frame_interval_ms_.median() : 0.0);
  }

  nlohmann::json stages = nlohmann::json::object();
  std::map<std::string, bool> names;
  for (const auto& [name, series] : stage_ms_) names[name] = true;
  for (const auto& [name, skips] : stage_skips_) names[name] = true;
  for (const auto& [name, unused] : names) {
    (void)unused;
    auto it = stage_ms_.find(name);
    const SampleSeries empty;
    const SampleSeries& series = it == stage_ms_.end() ? empty : it->second;
    auto skip_it = stage_skips_.find(name);
    nlohmann::json entry;
    entry["median_ms"] = finiteOrNull(series.median());
    entry["p95_ms"] = finiteOrNull(series.percentile(95.0));
    entry["runs"] = series.count();
    entry["skipped"] = skip_it == stage_skips_.end() ? 0 : skip_it->second;
    auto reasons_it = stage_skip_reasons_.find(name);
    if (reasons_it != stage_skip_reasons_.end()) entry["skip_reasons"] = reasons_it->second;
    stages[name] = entry;
  }
  out["stages"] = stages;

  nlohmann::json accuracy = nlohmann::json::object();
  nlohmann::json accuracy_detail = nlohmann::json::object();
  for (const auto& [measure, series] : accuracy_) {
    accuracy[measure] = finiteOrNull(series.median());
    accuracy_detail[measure] = {{"median", finiteOrNull(series.median())},
                                {"p95", finiteOrNull(series.percentile(95.0))},
                                {"max", finiteOrNull(series.max())},
                                {"mean", finiteOrNull(series.mean())},
                                {"samples", series.count()}};
  }
  out["accuracy"] = accuracy;
  out["accuracy_detail"] = accuracy_detail;
  out["counters"] = counters_;
  for (const auto& [key, value] : extra.items()) out[key] = value;
  return out;
}

void recordSeries(nlohmann::json& out, const std::string& name, const SampleSeries& series) {
  if (series.empty()) return;
  out[name] = {{"median", series.median()}, {"p95", series.percentile(95.0)}, {"max", series.max()},
               {"samples", series.count()}};
}

}  // namespace probelight
