// The run's machine-readable record (report.json): milliseconds per stage,
// error against the simulated truth, and counters. Other tools read the keys
// "frames", "fps", "stages" and "accuracy"; everything else may grow.
#pragma once

#include <chrono>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace probelight {

// Statistics over the most recent kWindow samples (a kiosk runs for weeks:
// keeping every frame's timings would grow without bound); count() is all
// samples ever added. 8192 samples (2 minutes at 60 fps, 64 KiB a series)
// put a p95 within a fraction of a percentile of the whole window's; with
// 65536 the dozen series grew the process by 3.75 MiB (1.5%) over its first
// 65536 frames, which a soak cannot tell from a leak.
class SampleSeries {
 public:
  static constexpr size_t kWindow = 8192;
  void add(double value) {
    if (values_.size() < kWindow)
      values_.push_back(value);
    else
      values_[total_ % kWindow] = value;
    ++total_;
  }
  size_t count() const { return total_; }
  bool empty() const { return values_.empty(); }
  // Nearest-rank percentile, p in [0, 100]; 0 when empty.
  double percentile(double p) const;
  double median() const { return percentile(50.0); }
  // The value added last; 0 when empty.
  double latest() const { return values_.empty() ? 0.0 : values_[(total_ - 1) % kWindow]; }
  double max() const;
  double mean() const;

 private:
  std::vector<double> values_;
  size_t total_ = 0;
};

// JSON has no NaN or infinity; a non-finite figure becomes null so that the
// file stays valid and the gap is visible.
inline nlohmann::json finiteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

// `series` as {median, p95, max, samples} under `name` in `out`; nothing
// when it is empty.
void recordSeries(nlohmann::json& out, const std::string& name, const SampleSeries& series);

class RunReport {
 public:
  void recordStageMs(const std::string& stage, double ms) { stage_ms_[stage].add(ms); }
  void recordStageSkip(const std::string& stage, const std::string& reason);
  void recordAccuracy(const std::string& measure, double value) { accuracy_[measure].add(value); }
  void count(const std::string& counter, long long by = 1) { counters_[counter] += by; }
  // A frame was shown at `now_s` (monotonic): the interval since the last
  // one is kept, so the report's steady frame rate is not dragged down by
  // start-up (the first fit, the first shadow maps) as frames / elapsed is.
  void recordFrameShown(double now_s) {
    if (last_frame_shown_s_ >= 0.0) frame_interval_ms_.add(1e3 * (now_s - last_frame_shown_s_));
    last_frame_shown_s_ = now_s;
  }

  const SampleSeries* stage(const std::string& name) const;
  const SampleSeries* accuracy(const std::string& name) const;
  long long counter(const std::string& name) const;

  // frames: frames processed; elapsed_s: wall time of the frame loop.
  nlohmann::json toJson(long long frames, double elapsed_s) const;

  nlohmann::json extra = nlohmann::json::object();  // free-form sections (config, gl, status)

 private:
  std::map<std::string, SampleSeries> stage_ms_;
  std::map<std::string, int> stage_skips_;
  std::map<std::string, std::map<std::string, int>> stage_skip_reasons_;
  std::map<std::string, SampleSeries> accuracy_;
  std::map<std::string, long long> counters_;
  SampleSeries frame_interval_ms_;
  double last_frame_shown_s_ = -1.0;
};

// Times a scope and records it under `stage` when it ends.
class StageTimer {
 public:
  StageTimer(RunReport& report, std::string stage)
      : report_(report), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
  ~StageTimer() {
    const auto elapsed = std::chrono::steady_clock::now() - start_;
    report_.recordStageMs(stage_, std::chrono::duration<double, std::milli>(elapsed).count());
  }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  RunReport& report_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace probelight
