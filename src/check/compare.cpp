#include "qdmr/check/compare.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>

#include "codec/backend.hpp"

namespace qdmr {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// |a - b|, 0 for bit-identical values (also two NaNs or equal infinities), +inf when only one is finite or they
// are different non-finite values.
double channel_delta(float a, float b) {
  if (std::memcmp(&a, &b, sizeof a) == 0 || (std::isnan(a) && std::isnan(b))) return 0.0;
  if (!std::isfinite(a) || !std::isfinite(b)) return kInf;
  return std::abs(double(a) - double(b));
}

std::size_t index(const Image& image, int x, int y) {
  return (std::size_t(y) * std::size_t(image.width) + std::size_t(x)) * std::size_t(image.channels);
}

bool pixel_within(const Image& rendered, std::size_t r, const Image& golden, std::size_t g, double bound) {
  for (int c = 0; c < rendered.channels; ++c)
    if (!(channel_delta(rendered.texels[r + std::size_t(c)], golden.texels[g + std::size_t(c)]) <= bound)) return false;
  return true;
}

// A golden pixel within `radius` (a square window) that matches the rendered pixel at (x, y).
bool neighbour_matches(const Image& rendered, const Image& golden, int x, int y, int radius, double bound) {
  for (int gy = std::max(0, y - radius); gy <= std::min(golden.height - 1, y + radius); ++gy)
    for (int gx = std::max(0, x - radius); gx <= std::min(golden.width - 1, x + radius); ++gx)
      if (pixel_within(rendered, index(rendered, x, y), golden, index(golden, gx, gy), bound)) return true;
  return false;
}

std::string number(double value) {
  std::ostringstream out;
  out << std::setprecision(4) << value;
  return out.str();
}

std::int64_t count_nonfinite(const Image& image, int* first_x, int* first_y) {
  std::int64_t count = 0;
  for (std::size_t i = 0; i < image.texels.size(); ++i)
    if (!std::isfinite(image.texels[i]) && count++ == 0) {
      const std::size_t pixel = i / std::size_t(image.channels);
      *first_x = int(pixel % std::size_t(image.width));
      *first_y = int(pixel / std::size_t(image.width));
    }
  return count;
}

const char* channel_name(int channel, int channels) {
  static const char* const rgba[] = {"R", "G", "B", "A"};
  static const char* const numbered[] = {"0", "1", "2", "3"};
  return channels >= 3 ? rgba[channel] : numbered[channel];
}

}  // namespace

std::string Comparison::summary() const {
  if (!comparable) return failures.empty() ? "not comparable" : failures.front();
  std::ostringstream out;
  out << "max |delta| " << number(max_abs);
  if (max_abs > 0)
    out << " at (" << worst_x << ", " << worst_y << ") " << channel_name(worst_channel, channels);
  out << ", pixels differing " << pixels_differing << ", over the bound " << pixels_over << ", rmse " << number(rmse)
      << ", psnr " << (std::isinf(psnr) ? std::string("inf") : number(psnr)) << " dB";
  return out.str();
}

Comparison compare_images(const Image& rendered, const Image& golden, const Tolerance& tolerance) {
  Comparison result;
  result.width = rendered.width;
  result.height = rendered.height;
  result.channels = rendered.channels;
  if (rendered.width != golden.width || rendered.height != golden.height || rendered.channels != golden.channels) {
    result.comparable = false;
    result.failures.push_back("size: rendered " + std::to_string(rendered.width) + "x" + std::to_string(rendered.height) +
                              " with " + std::to_string(rendered.channels) + " channel(s), golden " +
                              std::to_string(golden.width) + "x" + std::to_string(golden.height) + " with " +
                              std::to_string(golden.channels));
    return result;
  }
  int nx = 0, ny = 0;
  result.nonfinite_rendered = count_nonfinite(rendered, &nx, &ny);
  if (result.nonfinite_rendered > 0)
    result.failures.push_back("non-finite: " + std::to_string(result.nonfinite_rendered) +
                              " NaN or infinite value(s) in the rendered image, the first at (" + std::to_string(nx) +
                              ", " + std::to_string(ny) + ")");
  result.nonfinite_golden = count_nonfinite(golden, &nx, &ny);
  if (result.nonfinite_golden > 0)
    result.failures.push_back("non-finite: " + std::to_string(result.nonfinite_golden) +
                              " NaN or infinite value(s) in the golden image, the first at (" + std::to_string(nx) +
                              ", " + std::to_string(ny) + ")");

  double sum_squares = 0;
  for (int y = 0; y < rendered.height; ++y)
    for (int x = 0; x < rendered.width; ++x) {
      const std::size_t i = index(rendered, x, y);
      double pixel_max = 0;
      for (int c = 0; c < rendered.channels; ++c) {
        const double d = channel_delta(rendered.texels[i + std::size_t(c)], golden.texels[i + std::size_t(c)]);
        sum_squares += d * d;
        if (d > pixel_max) pixel_max = d;
        if (d > result.max_abs) {
          result.max_abs = d;
          result.worst_x = x;
          result.worst_y = y;
          result.worst_channel = c;
        }
      }
      if (pixel_max > 0) ++result.pixels_differing;
      if (pixel_max > tolerance.max_abs &&
          (tolerance.radius == 0 || !neighbour_matches(rendered, golden, x, y, tolerance.radius, tolerance.max_abs)))
        ++result.pixels_over;
    }
  const double values = double(rendered.texels.size());
  result.rmse = values > 0 ? std::sqrt(sum_squares / values) : 0.0;
  result.psnr = result.rmse > 0 ? 20.0 * std::log10(1.0 / result.rmse) : kInf;

  const std::int64_t pixels = std::int64_t(rendered.width) * rendered.height;
  std::int64_t allowed = 0;
  if (tolerance.max_pixels || tolerance.max_fraction) {
    allowed = std::numeric_limits<std::int64_t>::max();
    if (tolerance.max_pixels) allowed = std::min(allowed, *tolerance.max_pixels);
    if (tolerance.max_fraction) allowed = std::min(allowed, std::int64_t(std::floor(*tolerance.max_fraction * double(pixels))));
  }
  if (result.pixels_over > allowed) {
    std::ostringstream line;
    line << "pixels over max_abs " << number(tolerance.max_abs) << ": " << result.pixels_over << " ("
         << number(100.0 * double(result.pixels_over) / double(pixels)) << " %), allowed " << allowed;
    if (tolerance.radius > 0) line << " (radius " << tolerance.radius << ")";
    line << "; worst |delta| " << number(result.max_abs) << " at (" << result.worst_x << ", " << result.worst_y << ") "
         << channel_name(result.worst_channel, result.channels);
    result.failures.push_back(line.str());
  }
  if (tolerance.max_rmse && !(result.rmse <= *tolerance.max_rmse))
    result.failures.push_back("rmse " + number(result.rmse) + " > max_rmse " + number(*tolerance.max_rmse));
  if (tolerance.min_psnr && !(result.psnr >= *tolerance.min_psnr))
    result.failures.push_back("psnr " + number(result.psnr) + " dB < min_psnr " + number(*tolerance.min_psnr) + " dB");
  return result;
}

Image read_comparable_image(const std::filesystem::path& file, int* bits_version) {
  Image image = read_image(file, file.string());
  const std::size_t row = std::size_t(image.width) * std::size_t(image.channels);
  for (int y = 0; y < image.height / 2; ++y)  // read_image gives the rows bottom-up
    std::swap_ranges(image.texels.begin() + std::ptrdiff_t(std::size_t(y) * row),
                     image.texels.begin() + std::ptrdiff_t(std::size_t(y + 1) * row),
                     image.texels.begin() + std::ptrdiff_t(std::size_t(image.height - 1 - y) * row));
  if (bits_version) {
    *bits_version = 0;
    std::string error;
    if (const imageio::ReadFile in(file.string(), error); in) {
      const std::string& text = in.spec().bits_version;
      const std::string& software = in.spec().software;  // TIFF: "qdmr 0.1.0 (bits version 1)"
      const auto at = software.find("(bits version ");
      if (!text.empty())
        *bits_version = std::atoi(text.c_str());
      else if (software.starts_with("qdmr ") && at != std::string::npos)
        *bits_version = std::atoi(software.c_str() + at + 14);
    }
  }
  return image;
}

Image difference_heatmap(const Image& rendered, const Image& golden, double scale) {
  std::vector<float> values(std::size_t(rendered.width) * std::size_t(rendered.height));
  std::vector<bool> nonfinite(values.size());
  for (std::size_t p = 0; p < values.size(); ++p) {
    double pixel_max = 0;
    for (int c = 0; c < rendered.channels; ++c) {
      const std::size_t i = p * std::size_t(rendered.channels) + std::size_t(c);
      pixel_max = std::max(pixel_max, channel_delta(rendered.texels[i], golden.texels[i]));
    }
    nonfinite[p] = std::isinf(pixel_max);
    values[p] = scale > 0 ? float(std::min(1.0, pixel_max / scale)) : 0.0f;
  }
  Image heatmap(rendered.width, rendered.height, 3);
  imageio::backend().color_map(values.data(), rendered.width, rendered.height, "magma", heatmap.texels.data());
  for (std::size_t p = 0; p < values.size(); ++p)
    if (nonfinite[p]) std::fill_n(heatmap.texels.begin() + std::ptrdiff_t(3 * p), 3, 1.0f);
  return heatmap;
}

std::vector<std::int64_t> delta_histogram(const Image& rendered, const Image& golden) {
  std::vector<std::int64_t> bins(kDeltaBins, 0);
  const std::size_t pixels = std::size_t(rendered.width) * std::size_t(rendered.height);
  for (std::size_t p = 0; p < pixels; ++p) {
    double pixel_max = 0;
    for (int c = 0; c < rendered.channels; ++c) {
      const std::size_t i = p * std::size_t(rendered.channels) + std::size_t(c);
      pixel_max = std::max(pixel_max, channel_delta(rendered.texels[i], golden.texels[i]));
    }
    int bin = 0;
    if (pixel_max > 1.0)
      bin = kDeltaBins - 1;
    else if (pixel_max > 0)  // (1e-(k+1), 1e-k] for k = 7 .. 0 into bins 1 .. 8
      bin = std::clamp(8 + int(std::ceil(std::log10(pixel_max))), 1, kDeltaBins - 2);
    ++bins[std::size_t(bin)];
  }
  return bins;
}

std::string delta_bin_label(int bin) {
  static const char* const labels[kDeltaBins] = {"0",     "<=1e-7", "<=1e-6", "<=1e-5", "<=1e-4",
                                                 "<=1e-3", "<=0.01", "<=0.1",  "<=1",    ">1"};
  return labels[bin];
}

}  // namespace qdmr
