// JUnit XML and the HTML report of a check run: see qdmr/check/check.hpp.
#include <iomanip>

#include <nlohmann/json.hpp>
#include <sstream>

#include "file/atomic_file.hpp"
#include "qdmr/check/check.hpp"
#include "qdmr/core/version.hpp"

namespace qdmr {
namespace {

std::string escape(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (c < 0x20 && c != '\n' && c != '\t') out += ' ';  // not allowed in XML 1.0
        else out += char(c);
    }
  }
  return out;
}

std::string join(const std::vector<std::string>& lines) {
  std::string out;
  for (const std::string& line : lines) out += (out.empty() ? "" : "\n") + line;
  return out;
}

std::string seconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << s;
  return out.str();
}

int count(const CheckRun& run, CheckStatus status) {
  int n = 0;
  for (const CheckResult& r : run.results) n += r.status == status ? 1 : 0;
  return n;
}

}  // namespace

void write_junit(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& file) {
  const std::string suite = manifest.file.filename().string();
  std::ostringstream xml;
  const int failures = count(run, CheckStatus::Failed), errors = count(run, CheckStatus::Error),
            skipped = count(run, CheckStatus::Skipped);
  xml << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<testsuites name=\"qdmr check\" tests=\"" << run.results.size() << "\" failures=\"" << failures
      << "\" errors=\"" << errors << "\" skipped=\"" << skipped << "\" time=\"" << seconds(run.seconds) << "\">\n"
      << "  <testsuite name=\"" << escape(suite) << "\" tests=\"" << run.results.size() << "\" failures=\""
      << failures << "\" errors=\"" << errors << "\" skipped=\"" << skipped << "\" time=\"" << seconds(run.seconds)
      << "\">\n"
      << "    <properties>\n"
      << "      <property name=\"qdmr_version\" value=\"" << version() << "\"/>\n"
      << "      <property name=\"bits_version\" value=\"" << kBitsVersion << "\"/>\n"
      << "      <property name=\"manifest\" value=\"" << escape(manifest.file.string()) << "\"/>\n"
      << "    </properties>\n";
  for (const CheckResult& r : run.results) {
    xml << "    <testcase classname=\"qdmr.check." << escape(manifest.file.stem().string()) << "\" name=\""
        << escape(r.name) << "\" time=\"" << seconds(r.seconds) << "\"";
    const std::string message = r.lines.empty() ? "" : r.lines.front();
    if (r.status == CheckStatus::Passed) {
      xml << "/>\n";
      continue;
    }
    xml << ">\n";
    if (r.status == CheckStatus::Failed)
      xml << "      <failure message=\"" << escape(message) << "\" type=\"image mismatch\">" << escape(join(r.lines))
          << "</failure>\n";
    else if (r.status == CheckStatus::Error)
      xml << "      <error message=\"" << escape(message) << "\" type=\"cannot run\">" << escape(join(r.lines))
          << "</error>\n";
    else if (r.status == CheckStatus::Skipped)
      xml << "      <skipped message=\"" << escape(message) << "\"/>\n";
    if (!r.diff_folder.empty() || r.status == CheckStatus::Updated)
      xml << "      <system-out>"
          << escape(r.status == CheckStatus::Updated ? join(r.lines) : "diff folder: " + r.diff_folder.string())
          << "</system-out>\n";
    xml << "    </testcase>\n";
  }
  xml << "  </testsuite>\n</testsuites>\n";
  write_text_file(file, xml.str());
}

void write_results_json(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& file) {
  nlohmann::ordered_json document;
  document["manifest"] = manifest.file.string();
  document["qdmr_version"] = version();
  document["bits_version"] = kBitsVersion;
  document["seconds"] = run.seconds;
  document["exit_code"] = run.exit_code();
  document["checks"] = nlohmann::ordered_json::array();
  for (const CheckResult& r : run.results) {
    nlohmann::ordered_json check{{"name", r.name}, {"status", check_status_name(r.status)}, {"lines", r.lines}};
    for (const OutputResult& o : r.outputs) check["hashes"][o.output] = o.hash;
    check["prepare_ms"] = r.prepare_ms;
    check["draw_ms"] = r.draw_ms;
    check["seconds"] = r.seconds;
    if (!r.diff_folder.empty()) check["diff_folder"] = r.diff_folder.string();
    document["checks"].push_back(std::move(check));
  }
  write_text_file(file, document.dump(2) + "\n");
}

void write_html_report(const Manifest& manifest, const CheckRun& run, const std::filesystem::path& dir) {
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>qdmr check: "
       << escape(manifest.file.filename().string()) << "</title>\n<style>\n"
       << "body{font-family:sans-serif;margin:1.5em;color:#222}table{border-collapse:collapse}"
          "td,th{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}"
          ".PASS{color:#2a7a2a}.FAIL,.ERROR{color:#b3223d;font-weight:bold}.SKIP{color:#777}.UPDATED{color:#a66a00}"
          "figure{display:inline-block;margin:0 1em 1em 0}figure img{max-width:480px;image-rendering:pixelated;"
          "border:1px solid #ccc}pre{background:#f6f6f6;padding:6px;white-space:pre-wrap}\n"
       << "</style></head><body>\n<h1>qdmr check: " << escape(manifest.file.filename().string()) << "</h1>\n<p>"
       << run.results.size() << " checks: " << count(run, CheckStatus::Passed) << " passed, "
       << count(run, CheckStatus::Failed) << " failed, " << count(run, CheckStatus::Error) << " could not run, "
       << count(run, CheckStatus::Skipped) << " skipped, " << count(run, CheckStatus::Updated) << " updated; "
       << seconds(run.seconds) << " s. qdmr " << version() << ", bits version " << kBitsVersion << ".</p>\n";
  html << "<table><tr><th>check</th><th>result</th><th>draw ms</th><th>first line</th></tr>\n";
  for (const CheckResult& r : run.results) {
    const char* status = check_status_name(r.status);
    html << "<tr><td>";
    if (!r.diff_folder.empty()) html << "<a href=\"#" << escape(r.name) << "\">";
    html << escape(r.name) << (r.diff_folder.empty() ? "" : "</a>") << "</td><td class=\"" << status << "\">"
         << status << "</td><td>" << std::fixed << std::setprecision(1) << r.draw_ms << "</td><td>"
         << escape(r.lines.empty() ? "" : r.lines.front()) << "</td></tr>\n";
  }
  html << "</table>\n";
  for (const CheckResult& r : run.results) {
    if (r.diff_folder.empty()) continue;
    const std::filesystem::path folder = std::filesystem::relative(r.diff_folder, dir);
    html << "<h2 id=\"" << escape(r.name) << "\">" << escape(r.name) << "</h2>\n<pre>" << escape(join(r.lines))
         << "</pre>\n";
    for (const OutputResult& o : r.outputs) {
      html << "<h3>" << escape(o.output) << "</h3>\n<div>";
      const std::pair<const char*, const char*> views[] = {{".rendered.png", "rendered"},
                                                           {".golden.png", "golden"},
                                                           {".diff.png", "difference (largest channel, magma)"},
                                                           {".histogram.svg", "pixels by difference"}};
      for (const auto& [suffix, caption] : views) {
        const std::filesystem::path file = folder / (o.output + suffix);
        if (!std::filesystem::exists(dir / file)) continue;
        html << "<figure><img src=\"" << escape(file.generic_string()) << "\" alt=\"" << escape(o.output) << " "
             << caption << "\"><figcaption>" << caption << "</figcaption></figure>";
      }
      html << "</div>\n";
    }
  }
  html << "</body></html>\n";
  std::filesystem::create_directories(dir);
  write_text_file(dir / "index.html", html.str());
}

}  // namespace qdmr
