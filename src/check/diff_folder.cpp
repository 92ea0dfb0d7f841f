#include "check/diff_folder.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "codec/image_file.hpp"
#include "file/atomic_file.hpp"
#include "qdmr/check/compare.hpp"
#include "qdmr/write/write.hpp"

namespace qdmr {
namespace {

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// A frame holding `image` as its colour (linear) or as the AOV, so the writer's views apply to goldens too.
Frame frame_of(const Image& image, std::optional<Aov> aov) {
  Frame frame;
  frame.width = image.width;
  frame.height = image.height;
  PixelBuffer pixels(image.texels.begin(), image.texels.end());
  if (aov)
    frame.aovs.push_back({*aov, image.channels, std::move(pixels)});
  else
    frame.color = std::move(pixels);
  return frame;
}

void write_output(const Frame& frame, std::optional<Aov> aov, const std::filesystem::path& file) {
  if (aov)
    write_aov(frame, *aov, file);
  else
    write_frame(frame, file);
}

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

}  // namespace

void write_display_png(const Image& image, const std::filesystem::path& file) {
  std::vector<std::uint8_t> bytes(image.texels.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const float v = std::isfinite(image.texels[i]) ? std::clamp(image.texels[i], 0.0f, 1.0f) : 0.0f;
    bytes[i] = std::uint8_t(std::floor(v * 255.0f + 0.5f));
  }
  const imageio::WriteSpec spec{image.width, image.height, image.channels, imageio::PixelType::UInt8, {}, {{"oiio:ColorSpace", "sRGB"}}, {}};
  write_image_file(file, spec, bytes.data(), "image");
}

std::string delta_histogram_svg(const std::vector<std::int64_t>& bins, const std::string& title) {
  constexpr int kBar = 44, kGap = 8, kLeft = 60, kTop = 36, kPlot = 160;
  const int width = kLeft + int(bins.size()) * (kBar + kGap) + 20;
  const int height = kTop + kPlot + 56;
  std::int64_t most = 1;
  for (std::int64_t b : bins) most = std::max(most, b);
  const double top = std::log10(double(most) + 1.0);
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << kLeft << "\" y=\"18\" font-size=\"13\">" << xml_escape(title) << "</text>\n"
      << "<text x=\"12\" y=\"" << kTop + kPlot / 2 << "\" transform=\"rotate(-90 12 " << kTop + kPlot / 2
      << ")\" text-anchor=\"middle\">pixels (log scale)</text>\n"
      << "<line x1=\"" << kLeft - 4 << "\" y1=\"" << kTop + kPlot << "\" x2=\"" << width - 10 << "\" y2=\""
      << kTop + kPlot << "\" stroke=\"#444\"/>\n";
  for (std::size_t i = 0; i < bins.size(); ++i) {
    const double h = bins[i] > 0 ? std::max(1.0, kPlot * std::log10(double(bins[i]) + 1.0) / top) : 0.0;
    const int x = kLeft + int(i) * (kBar + kGap);
    svg << "<rect x=\"" << x << "\" y=\"" << std::fixed << std::setprecision(1) << kTop + kPlot - h << "\" width=\""
        << kBar << "\" height=\"" << h << "\" fill=\"" << (i == 0 ? "#5b8f5b" : "#b3475d") << "\"/>\n"
        << "<text x=\"" << x + kBar / 2 << "\" y=\"" << kTop + kPlot - h - 4 << "\" text-anchor=\"middle\">"
        << bins[i] << "</text>\n"
        << "<text x=\"" << x + kBar / 2 << "\" y=\"" << kTop + kPlot + 16 << "\" text-anchor=\"middle\">"
        << xml_escape(delta_bin_label(int(i))) << "</text>\n";
  }
  svg << "<text x=\"" << kLeft + int(bins.size()) * (kBar + kGap) / 2 << "\" y=\"" << kTop + kPlot + 40
      << "\" text-anchor=\"middle\">largest channel difference of a pixel</text>\n</svg>\n";
  return svg.str();
}

DiffFolder::DiffFolder(std::filesystem::path folder) : folder_(std::move(folder)) {
  std::filesystem::create_directories(folder_);
  // A stale file of an earlier failure would mislead; only files with the names written here are removed.
  for (const auto& entry : std::filesystem::directory_iterator(folder_)) {
    const std::string name = entry.path().filename().string();
    const bool ours = name == "failures.txt" || name.find(".rendered.") != std::string::npos ||
                      name.find(".golden.") != std::string::npos || name.ends_with(".diff.png") ||
                      name.ends_with(".histogram.svg") || name.ends_with(".histogram.csv");
    if (ours && entry.is_regular_file()) std::filesystem::remove(entry.path());
  }
}

void DiffFolder::add_comparison(const std::string& output, const Frame& frame, std::optional<Aov> aov,
                                const Image& rendered, const Image& golden, const std::filesystem::path& golden_file) {
  const std::string ext = lower_extension(golden_file);
  write_output(frame, aov, folder_ / (output + ".rendered" + ext));
  copy_file_atomically(golden_file, folder_ / (output + ".golden" + ext));
  if (ext != ".png") {
    write_output(frame, aov, folder_ / (output + ".rendered.png"));
    if (ext == ".exr")
      write_output(frame_of(golden, aov), aov, folder_ / (output + ".golden.png"));
    else
      write_display_png(golden, folder_ / (output + ".golden.png"));  // a TIFF holds sRGB codes already
  }
  if (rendered.width != golden.width || rendered.height != golden.height || rendered.channels != golden.channels) {
    notes_.push_back(output + ": no heatmap or histogram, the sizes differ");
    return;
  }
  double scale = 0;
  for (std::size_t i = 0; i < rendered.texels.size(); ++i) {
    const double d = std::abs(double(rendered.texels[i]) - double(golden.texels[i]));
    if (std::isfinite(d)) scale = std::max(scale, d);
  }
  write_display_png(difference_heatmap(rendered, golden, scale), folder_ / (output + ".diff.png"));
  std::ostringstream note;
  note << output << ": " << output << ".diff.png shows the largest channel difference per pixel, black 0 to yellow "
       << std::setprecision(4) << scale << " (magma; white: not finite)";
  notes_.push_back(note.str());
  const std::vector<std::int64_t> bins = delta_histogram(rendered, golden);
  write_text_file(folder_ / (output + ".histogram.svg"),
                  delta_histogram_svg(bins, output + ": pixels by their largest channel difference"));
  std::string csv = "largest_channel_difference,pixels\n";
  for (std::size_t i = 0; i < bins.size(); ++i) csv += delta_bin_label(int(i)) + "," + std::to_string(bins[i]) + "\n";
  write_text_file(folder_ / (output + ".histogram.csv"), csv);
}

void DiffFolder::add_render(const std::string& output, const Frame& frame, std::optional<Aov> aov) {
  write_output(frame, aov, folder_ / (output + ".rendered.exr"));
  write_output(frame, aov, folder_ / (output + ".rendered.png"));
}

void DiffFolder::finish(const std::vector<std::string>& failures) {
  std::string text;
  for (const std::string& line : failures) text += line + "\n";
  if (!notes_.empty()) text += "\n";
  for (const std::string& line : notes_) text += line + "\n";
  write_text_file(folder_ / "failures.txt", text);
}

}  // namespace qdmr
