// Built row map against the true one (see map_comparison.hpp).
#include "rowloc/mapping/map_comparison.hpp"

#include "rowloc/geometry/segment_index.hpp"
#include "rowloc/mapio/local_frame.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

namespace rowloc::mapping {
namespace {

struct Sample {
  Eigen::Vector2d point;
  std::size_t row;
};

std::vector<Sample> SampleOutlines(const geometry::RowMap& map, double step) {
  std::vector<Sample> samples;
  for (std::size_t r = 0; r < map.rows.size(); ++r) {
    const geometry::Row& row = map.rows[r];
    for (std::size_t s = 0; s < row.SegmentCount(); ++s) {
      const auto [a, b] = row.Segment(s);
      const double length = (b - a).norm();
      const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(length / step)));
      for (std::size_t k = 0; k < n; ++k) {
        samples.push_back({a + (b - a) * (static_cast<double>(k) / static_cast<double>(n)), r});
      }
      if (!row.closed && s + 1 == row.SegmentCount()) samples.push_back({b, r});
    }
  }
  return samples;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1;
  const std::size_t index = std::min(values.size() - 1, k);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  return values[index];
}

double Rms(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

std::string BaseId(const std::string& id) {
  const auto dot = id.find(".part-");
  return dot == std::string::npos ? id : id.substr(0, dot);
}

}  // namespace

double LargestDistanceToOutlines(const geometry::RowMap& from, const geometry::RowMap& to, double step_m) {
  if (!(step_m > 0.0) || !std::isfinite(step_m)) {
    throw std::invalid_argument("LargestDistanceToOutlines: step_m must be positive");
  }
  std::vector<geometry::SegmentIndex::Entry> segments;
  for (std::size_t r = 0; r < to.rows.size(); ++r) {
    for (std::size_t s = 0; s < to.rows[r].SegmentCount(); ++s) {
      const auto [a, b] = to.rows[r].Segment(s);
      if ((b - a).norm() > 1e-9) segments.push_back({geometry::Segment2{a, b}, r, s});
    }
  }
  const std::vector<Sample> samples = SampleOutlines(from, step_m);
  if (samples.empty()) return 0.0;
  if (segments.empty()) return std::numeric_limits<double>::infinity();
  const geometry::SegmentIndex index(std::move(segments));
  double largest = 0.0;
  for (const Sample& sample : samples) largest = std::max(largest, index.Nearest(sample.point, 1).front().first);
  return largest;
}

MapComparison CompareRowMaps(const geometry::RowMap& built_in, const geometry::RowMap& truth,
                             const MapComparisonParams& params) {
  if (!(params.sample_step_m > 0.0) || !std::isfinite(params.sample_step_m) || !(params.match_distance_m > 0.0) ||
      !std::isfinite(params.match_distance_m)) {
    throw std::invalid_argument("CompareRowMaps: sample step and match distance must be positive");
  }
  if (built_in.rows.empty() || truth.rows.empty()) throw std::invalid_argument("CompareRowMaps: empty map");
  geometry::RowMap built = built_in;
  const auto& a = built.origin;
  const auto& b = truth.origin;
  if (a.latitude_deg != b.latitude_deg || a.longitude_deg != b.longitude_deg || a.altitude_m != b.altitude_m) {
    const mapio::LocalFrame from(a);
    const mapio::LocalFrame to(b);
    for (auto& row : built.rows) {
      for (auto& p : row.points_m) {
        const geometry::GeoOrigin g = from.ToGeodetic(Eigen::Vector3d(p.x(), p.y(), 0.0));
        p = to.ToEnu(g.latitude_deg, g.longitude_deg, g.altitude_m).head<2>();
      }
    }
    built.origin = truth.origin;
  }
  const geometry::SegmentIndex built_index = geometry::SegmentIndex::FromRowMap(built);
  const geometry::SegmentIndex truth_index = geometry::SegmentIndex::FromRowMap(truth);

  MapComparison result;
  result.truth_parts = truth.rows.size();
  result.built_parts = built.rows.size();
  std::set<std::string> truth_rows;
  std::set<std::string> built_rows;
  for (const auto& row : truth.rows) truth_rows.insert(BaseId(row.id));
  for (const auto& row : built.rows) built_rows.insert(BaseId(row.id));
  result.truth_rows = truth_rows.size();
  result.built_rows = built_rows.size();

  std::vector<double> all;
  std::vector<double> forward;
  std::vector<double> backward;
  // Built -> truth, per built part.
  const std::vector<Sample> built_samples = SampleOutlines(built, params.sample_step_m);
  std::vector<std::vector<double>> part_distances(built.rows.size());
  std::vector<Eigen::Vector2d> worst(built.rows.size(), Eigen::Vector2d::Zero());
  std::vector<double> worst_distance(built.rows.size(), -1.0);
  std::vector<std::map<std::size_t, std::size_t>> votes(built.rows.size());
  for (const Sample& s : built_samples) {
    const auto nearest = truth_index.Nearest(s.point, 1);
    const double d = nearest.front().first;
    const std::size_t truth_row = truth_index.entries()[nearest.front().second].row;
    if (d > worst_distance[s.row]) {
      worst_distance[s.row] = d;
      worst[s.row] = s.point;
    }
    part_distances[s.row].push_back(d);
    ++votes[s.row][truth_row];
    forward.push_back(d);
  }
  std::vector<bool> truth_found(truth.rows.size(), false);
  for (std::size_t r = 0; r < built.rows.size(); ++r) {
    PartMatch match;
    match.built_id = built.rows[r].id;
    match.p95_m = Percentile(part_distances[r], 0.95);
    match.rms_m = Rms(part_distances[r]);
    match.stated_sigma_m = built.rows[r].outline_sigma_m;
    match.worst_m = worst[r];
    match.max_m = part_distances[r].empty() ? 0.0 : *std::max_element(part_distances[r].begin(), part_distances[r].end());
    const auto best = std::max_element(votes[r].begin(), votes[r].end(),
                                       [](const auto& x, const auto& y) { return x.second < y.second; });
    if (best != votes[r].end() && Percentile(part_distances[r], 0.5) <= params.match_distance_m) {
      match.truth_id = truth.rows[best->first].id;
      truth_found[best->first] = true;
    } else {
      result.invented.push_back(match.built_id);
    }
    result.matches.push_back(match);
  }
  std::set<std::string> rows_found;
  for (std::size_t t = 0; t < truth.rows.size(); ++t) {
    if (truth_found[t]) {
      ++result.truth_parts_found;
      rows_found.insert(BaseId(truth.rows[t].id));
    } else {
      result.missed.push_back(truth.rows[t].id);
    }
  }
  result.truth_rows_found = rows_found.size();
  // Truth -> built.
  for (const Sample& s : SampleOutlines(truth, params.sample_step_m)) {
    backward.push_back(built_index.Nearest(s.point, 1).front().first);
  }
  all = forward;
  all.insert(all.end(), backward.begin(), backward.end());
  result.samples = all.size();
  result.p95_m = Percentile(all, 0.95);
  result.max_m = *std::max_element(all.begin(), all.end());
  result.built_to_truth_p95_m = Percentile(forward, 0.95);
  result.built_to_truth_rms_m = Rms(forward);
  double stated = 0.0;
  for (std::size_t r = 0; r < built.rows.size(); ++r) {
    stated += static_cast<double>(part_distances[r].size()) * built.rows[r].outline_sigma_m * built.rows[r].outline_sigma_m;
  }
  result.stated_sigma_rms_m = forward.empty() ? 0.0 : std::sqrt(stated / static_cast<double>(forward.size()));
  result.truth_to_built_p95_m = Percentile(backward, 0.95);
  return result;
}

std::string FormatMapComparison(const MapComparison& c) {
  std::string text = fmt::format(
      "rows: true {}, found {}; parts: true {}, built {}, found {}; missed: {}; invented: {}\n"
      "distance (both directions, {} samples): p95 {:.4f} m, max {:.4f} m (built->true p95 {:.4f} m, "
      "true->built p95 {:.4f} m)\nbuilt->true rms {:.4f} m; the built map's outline_sigma_m, rms {:.4f} m\n",
      c.truth_rows, c.truth_rows_found, c.truth_parts, c.built_parts, c.truth_parts_found,
      c.missed.empty() ? "none" : fmt::format("{}", fmt::join(c.missed, ", ")),
      c.invented.empty() ? "none" : fmt::format("{}", fmt::join(c.invented, ", ")), c.samples, c.p95_m, c.max_m,
      c.built_to_truth_p95_m, c.truth_to_built_p95_m, c.built_to_truth_rms_m, c.stated_sigma_rms_m);
  for (const auto& m : c.matches) {
    text += fmt::format("  {:<18} -> {:<18} p95 {:.4f} m, max {:.4f} m at ({:.2f}, {:.2f}), rms {:.4f} m (stated {:.4f} m)\n",
                        m.built_id, m.truth_id.empty() ? "(invented)" : m.truth_id, m.p95_m, m.max_m, m.worst_m.x(),
                        m.worst_m.y(), m.rms_m, m.stated_sigma_m);
  }
  return text;
}

std::string FormatMapComparisonJson(const MapComparison& c) {
  nlohmann::ordered_json j;
  j["truth_rows"] = c.truth_rows;
  j["truth_rows_found"] = c.truth_rows_found;
  j["truth_parts"] = c.truth_parts;
  j["built_parts"] = c.built_parts;
  j["truth_parts_found"] = c.truth_parts_found;
  j["missed"] = c.missed;
  j["invented"] = c.invented;
  j["samples"] = c.samples;
  j["p95_m"] = c.p95_m;
  j["max_m"] = c.max_m;
  j["built_to_truth_p95_m"] = c.built_to_truth_p95_m;
  j["truth_to_built_p95_m"] = c.truth_to_built_p95_m;
  j["built_to_truth_rms_m"] = c.built_to_truth_rms_m;
  j["stated_sigma_rms_m"] = c.stated_sigma_rms_m;
  nlohmann::ordered_json parts = nlohmann::ordered_json::array();
  for (const auto& m : c.matches) {
    parts.push_back({{"built_id", m.built_id}, {"truth_id", m.truth_id}, {"p95_m", m.p95_m}, {"max_m", m.max_m},
                     {"rms_m", m.rms_m}, {"stated_sigma_m", m.stated_sigma_m}});
  }
  j["parts"] = std::move(parts);
  return j.dump(2) + "\n";
}

}  // namespace rowloc::mapping
