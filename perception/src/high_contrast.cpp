#include "colorfree/perception/high_contrast.h"

#include <algorithm>
#include <cmath>

#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

namespace {
constexpr int kBins = 32;
}

HighContrastParams HighContrastParams::load(const std::string& path) {
  ParamFile f(path);
  HighContrastParams p;
  p.window_px = static_cast<int>(f.getInRange("window_px", 4, 64));
  p.min_contrast = f.getInRange("min_contrast", 0, 128);
  p.light_contrast_fraction = f.getInRange("light_contrast_fraction", 0, 1);
  p.light_min_contrast = f.getInRange("light_min_contrast", 0, 128);
  p.sparse_max_seed_fraction = f.getInRange("sparse_max_seed_fraction", 0, 1);
  p.sparse_light_contrast_fraction = f.getInRange("sparse_light_contrast_fraction", 0, 1);
  p.row_step_px = static_cast<int>(f.getInRange("row_step_px", 1, 8));
  p.dilation_windows = static_cast<int>(f.getInRange("dilation_windows", 0, 8));
  f.finish();
  return p;
}

HighContrastParams HighContrastParams::loadDefault() {
  return load(defaultParamDir() + "/high_contrast.yaml");
}

int ContrastRegions::markedCount() const {
  return static_cast<int>(std::count(mask.begin(), mask.end(), std::uint8_t{1}));
}

OtsuResult otsuBinned(const std::uint32_t* count, const std::uint32_t* value_sum, int bins) {
  OtsuResult best;
  int lo = 0;
  while (lo < bins && count[lo] == 0) ++lo;
  int hi = bins - 1;
  while (hi >= 0 && count[hi] == 0) --hi;
  if (lo >= hi) {
    if (lo < bins) best.mean0 = best.mean1 = static_cast<double>(value_sum[lo]) / count[lo];
    best.threshold = static_cast<int>(best.mean0);
    return best;
  }
  double total = 0, total_sum = 0;
  for (int b = lo; b <= hi; ++b) {
    total += count[b];
    total_sum += value_sum[b];
  }
  double n0 = 0, sum0 = 0, best_score = -1;
  int best_bin = lo;
  for (int b = lo; b < hi; ++b) {
    n0 += count[b];
    sum0 += value_sum[b];
    if (count[b] == 0) continue;  // the same split as the previous bin
    const double n1 = total - n0;
    const double diff = (total_sum - sum0) * n0 - sum0 * n1;  // (m1 − m0) n0 n1
    // Between-class variance n0 n1 (m1 − m0)², up to the constant 1 / total².
    const double score = diff * diff / (n0 * n1);
    if (score > best_score) {
      best_score = score;
      best_bin = b;
      best.mean0 = sum0 / n0;
      best.mean1 = (total_sum - sum0) / n1;
    }
  }
  best.threshold = best_bin;
  best.between_std = std::sqrt(best_score) / total;
  return best;
}

OtsuResult otsu(const std::uint32_t* hist) {
  std::uint32_t value_sum[256];
  for (int v = 0; v < 256; ++v) value_sum[v] = static_cast<std::uint32_t>(v) * hist[v];
  return otsuBinned(hist, value_sum, 256);
}

HighContrastDetector::HighContrastDetector(HighContrastParams params) : params_(params) {}

ContrastRegions HighContrastDetector::run(const GrayView& image, const IgnoreMask& ignore,
                                          std::optional<double> light_gray) const {
  if (ignore.width != image.width || ignore.height != image.height) {
    throw Error("high-contrast regions: ignore mask does not match the image size");
  }
  const int s = params_.window_px;
  ContrastRegions out;
  out.window_px = s;
  out.columns = image.width / s;
  out.rows = image.height / s;
  const std::size_t n = static_cast<std::size_t>(out.columns) * out.rows;
  out.seeds.assign(n, 0);
  out.mask.assign(n, 0);
  out.contrast.assign(n, 0.f);
  const int used_width = out.columns * s;
  // The bar for this frame's light, and the lower bar of a sparse frame (see the parameters).
  const bool sparse_test = params_.sparse_max_seed_fraction > 0;
  const double light = params_.light_contrast_fraction > 0 || sparse_test
                           ? (light_gray ? *light_gray : frameLightGray(image, ignore))
                           : 0;
  const auto bar = [&](double fraction) {
    return fraction > 0 ? std::min(params_.min_contrast,
                                   std::max(params_.light_min_contrast, fraction * light))
                        : params_.min_contrast;
  };
  const double min_contrast = bar(params_.light_contrast_fraction);
  const double sparse_contrast =
      sparse_test ? std::min(min_contrast, bar(params_.sparse_light_contrast_fraction))
                  : min_contrast;
  // (Windows are looked at down to the lower bar; seeds are chosen when all are known.)
  const double min_var = sparse_contrast * sparse_contrast;
  const double frame_min_var = min_contrast * min_contrast;
  int looked_count = 0;
  std::vector<std::uint8_t> under_frame_bar;  // windows only the lower bar's pre-test let through
  if (sparse_contrast < min_contrast) under_frame_bar.assign(n, 0);
  const int step = params_.row_step_px;
  const double count = static_cast<double>(s) * ((s + step - 1) / step);

  std::vector<std::uint32_t> col_sum(used_width), col_sq(used_width);
  std::vector<std::uint8_t> looked(out.columns);
  for (int r = 0; r < out.rows; ++r) {
    const int cy = r * s + s / 2;
    bool any = false;
    for (int c = 0; c < out.columns; ++c) {
      looked[c] = ignore.looked(c * s + s / 2, cy) ? 1 : 0;
      any = any || looked[c];
    }
    if (!any) continue;
    // Column sums over the window row, vectorised along x; windows then add up their columns.
    std::fill(col_sum.begin(), col_sum.end(), 0u);
    std::fill(col_sq.begin(), col_sq.end(), 0u);
    for (int y = r * s; y < (r + 1) * s; y += step) {
      const std::uint8_t* row = image.row(y);
      std::uint32_t* sum = col_sum.data();
      std::uint32_t* sq = col_sq.data();
      for (int x = 0; x < used_width; ++x) {
        const std::uint32_t v = row[x];
        sum[x] += v;
        sq[x] += v * v;
      }
    }
    for (int c = 0; c < out.columns; ++c) {
      if (!looked[c]) continue;
      ++looked_count;
      std::uint32_t sum = 0, sq = 0;
      for (int x = c * s; x < (c + 1) * s; ++x) {
        sum += col_sum[x];
        sq += col_sq[x];
      }
      const double mean = sum / count;
      const double var = sq / count - mean * mean;
      // Otsu's between-class variance never exceeds the window's variance.
      if (var < min_var) continue;
      if (var < frame_min_var) under_frame_bar[static_cast<std::size_t>(r) * out.columns + c] = 1;
      // Otsu over 32 bins of 8 gray levels; each bin keeps the sum of its values, so the class
      // means (and the contrast) are exact for thresholds between bins. A bin's count (high 32
      // bits) and value sum (low 32 bits, at most 64 * 64 * 255) share one counter, so a pixel
      // costs one add; two interleaved histograms halve the stalls on repeated bins.
      std::uint64_t packed[2][kBins] = {};
      for (int y = r * s; y < (r + 1) * s; y += step) {
        const std::uint8_t* row = image.row(y) + c * s;
        int x = 0;
        for (; x + 1 < s; x += 2) {
          packed[0][row[x] >> 3] += (std::uint64_t{1} << 32) | row[x];
          packed[1][row[x + 1] >> 3] += (std::uint64_t{1} << 32) | row[x + 1];
        }
        if (x < s) packed[0][row[x] >> 3] += (std::uint64_t{1} << 32) | row[x];
      }
      std::uint32_t bin_count[kBins], value_sum[kBins];
      for (int b = 0; b < kBins; ++b) {
        const std::uint64_t v = packed[0][b] + packed[1][b];
        bin_count[b] = static_cast<std::uint32_t>(v >> 32);
        value_sum[b] = static_cast<std::uint32_t>(v);
      }
      const OtsuResult o = otsuBinned(bin_count, value_sum, kBins);
      const std::size_t i = static_cast<std::size_t>(r) * out.columns + c;
      out.contrast[i] = static_cast<float>(o.between_std);
      if (o.between_std >= min_contrast) out.seeds[i] = 1;
    }
  }
  if (sparse_contrast < min_contrast) {
    const auto seeded = std::count(out.seeds.begin(), out.seeds.end(), std::uint8_t{1});
    if (seeded < params_.sparse_max_seed_fraction * looked_count) {
      for (std::size_t i = 0; i < n; ++i) out.seeds[i] = out.contrast[i] >= sparse_contrast;
    } else {
      // (As without the lower bar: 0 for a window the frame's own pre-test skips.)
      for (std::size_t i = 0; i < n; ++i) {
        if (under_frame_bar[i]) out.contrast[i] = 0;
      }
    }
  }

  const int d = params_.dilation_windows;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.columns; ++c) {
      if (!out.seeds[static_cast<std::size_t>(r) * out.columns + c]) continue;
      for (int rr = std::max(0, r - d); rr <= std::min(out.rows - 1, r + d); ++rr) {
        for (int cc = std::max(0, c - d); cc <= std::min(out.columns - 1, c + d); ++cc) {
          out.mask[static_cast<std::size_t>(rr) * out.columns + cc] = 1;
        }
      }
    }
  }

  // Connected regions (8-neighbourhood) of the marked windows.
  std::vector<int> label(n, -1);
  std::vector<int> stack;
  for (std::size_t start = 0; start < n; ++start) {
    if (!out.mask[start] || label[start] >= 0) continue;
    const int id = static_cast<int>(out.regions.size());
    ContrastRegion region;
    int c0 = out.columns, c1 = -1, r0 = out.rows, r1 = -1;
    stack.assign(1, static_cast<int>(start));
    label[start] = id;
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      const int r = i / out.columns, c = i % out.columns;
      ++region.window_count;
      c0 = std::min(c0, c);
      c1 = std::max(c1, c);
      r0 = std::min(r0, r);
      r1 = std::max(r1, r);
      for (int rr = std::max(0, r - 1); rr <= std::min(out.rows - 1, r + 1); ++rr) {
        for (int cc = std::max(0, c - 1); cc <= std::min(out.columns - 1, c + 1); ++cc) {
          const int j = rr * out.columns + cc;
          if (out.mask[j] && label[j] < 0) {
            label[j] = id;
            stack.push_back(j);
          }
        }
      }
    }
    region.box = {static_cast<double>(c0 * s), static_cast<double>(r0 * s),
                  static_cast<double>((c1 + 1) * s), static_cast<double>((r1 + 1) * s)};
    out.regions.push_back(region);
  }
  return out;
}

}  // namespace colorfree
