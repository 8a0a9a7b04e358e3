#include <gtest/gtest.h>

#include <cmath>

#include "stages/run_report.hpp"

namespace probelight {
namespace {

TEST(SampleSeries, NearestRankPercentiles) {
  SampleSeries series;
  for (int i = 1; i <= 20; ++i) series.add(static_cast<double>(21 - i));  // 20..1, unsorted input
  EXPECT_DOUBLE_EQ(series.median(), 10.0);         // rank ceil(0.5*20) = 10
  EXPECT_DOUBLE_EQ(series.percentile(95.0), 19.0);  // rank ceil(0.95*20) = 19
  EXPECT_DOUBLE_EQ(series.percentile(100.0), 20.0);
  EXPECT_DOUBLE_EQ(series.percentile(0.0), 1.0);
  EXPECT_DOUBLE_EQ(series.max(), 20.0);
  EXPECT_DOUBLE_EQ(series.mean(), 10.5);
}

// A kiosk runs for weeks: the series keeps the last kWindow samples (so its
// memory stops growing), counts them all, and its statistics are the
// window's.
TEST(SampleSeries, KeepsOnlyTheLatestWindowButCountsEverySample) {
  SampleSeries series;
  for (std::size_t i = 0; i < SampleSeries::kWindow; ++i) series.add(100.0);
  for (std::size_t i = 0; i < SampleSeries::kWindow; ++i) series.add(1.0);
  EXPECT_EQ(series.count(), 2 * SampleSeries::kWindow);
  EXPECT_DOUBLE_EQ(series.max(), 1.0);  // the 100s have all been overwritten
  EXPECT_DOUBLE_EQ(series.latest(), 1.0);
  EXPECT_LE(SampleSeries::kWindow * sizeof(double), 64u * 1024u) << "a series' memory, the soak's budget";
}

TEST(RunReport, HasTheKeysOtherToolsReadAndCountsSkips) {
  RunReport report;
  report.recordStageMs("detect", 2.0);
  report.recordStageMs("detect", 4.0);
  report.recordStageSkip("probe_to_cube", "no tag");
  report.recordStageSkip("probe_to_cube", "no tag");
  report.recordStageSkip("probe_to_cube", "ball out of view");
  report.recordAccuracy("pose_rotation_error_deg", 0.1);
  report.count("frames_without_tag", 2);
  const nlohmann::json json = report.toJson(10, 2.0);
  EXPECT_EQ(json["frames"], 10);
  EXPECT_DOUBLE_EQ(json["fps"].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(json["stages"]["detect"]["median_ms"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(json["stages"]["detect"]["p95_ms"].get<double>(), 4.0);
  EXPECT_EQ(json["stages"]["detect"]["runs"], 2);
  EXPECT_EQ(json["stages"]["detect"]["skipped"], 0);
  EXPECT_EQ(json["stages"]["probe_to_cube"]["runs"], 0);
  EXPECT_EQ(json["stages"]["probe_to_cube"]["skipped"], 3);
  EXPECT_EQ(json["stages"]["probe_to_cube"]["skip_reasons"]["no tag"], 2);
  EXPECT_DOUBLE_EQ(json["accuracy"]["pose_rotation_error_deg"].get<double>(), 0.1);
  EXPECT_EQ(json["counters"]["frames_without_tag"], 2);
}

TEST(RunReport, NonFiniteFiguresBecomeNullNotInvalidJson) {
  RunReport report;
  report.recordAccuracy("broken", std::nan(""));
  const std::string text = report.toJson(1, 1.0).dump();
  EXPECT_EQ(text.find("nan"), std::string::npos);
  EXPECT_TRUE(nlohmann::json::parse(text)["accuracy"]["broken"].is_null());
}

}  // namespace
}  // namespace probelight
