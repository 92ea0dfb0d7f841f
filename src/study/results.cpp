#include "study/results.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "file/atomic_file.hpp"

namespace qdmr {
namespace {

std::string cell(const nlohmann::ordered_json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::ostringstream quoted;
    quoted << '"';
    for (char c : s) (c == '"' ? quoted << "\"\"" : quoted << c);
    quoted << '"';
    return quoted.str();
  }
  if (v.is_number_float()) {
    std::ostringstream out;
    out << std::setprecision(9) << v.get<double>();
    return out.str();
  }
  return cell(nlohmann::ordered_json(v.dump()));
}

// Column names of a group of the rows ("deterministic" or "timing"), in first-seen order.
std::vector<std::string> columns(const std::vector<StudyRow>& rows, const char* group) {
  std::vector<std::string> names;
  for (const StudyRow& row : rows)
    if (row.contains(group))
      for (const auto& item : row[group].items())
        if (std::find(names.begin(), names.end(), item.key()) == names.end()) names.push_back(item.key());
  return names;
}

// One line per row of `which`: the index, the axis values, the deterministic columns, the timing columns.
std::string csv(const nlohmann::ordered_json& header, const std::vector<StudyRow>& rows,
                const std::vector<std::size_t>& which, const std::string& first_column = "", const std::string& first_value = "") {
  const std::vector<std::string> axes = header["axes"].get<std::vector<std::string>>();
  const std::vector<std::string> det = columns(rows, "deterministic"), timing = columns(rows, "timing");
  std::ostringstream text;  // (string + string in a loop trips GCC 12's -Wrestrict)
  if (!first_column.empty()) text << first_column << ',';
  text << "index";
  for (const std::string& a : axes) text << ',' << a;
  for (const std::string& c : det) text << ',' << c;
  for (const std::string& c : timing) text << ',' << c;
  text << '\n';
  for (std::size_t r : which) {
    const StudyRow& row = rows[r];
    if (!first_column.empty()) text << first_value << ',';
    text << row["index"].get<std::size_t>();
    for (const std::string& a : axes) text << ',' << cell(row["config"].value(a, nlohmann::ordered_json()));
    for (const std::string& c : det) text << ',' << cell(row["deterministic"].value(c, nlohmann::ordered_json()));
    for (const std::string& c : timing) text << ',' << cell(row["timing"].value(c, nlohmann::ordered_json()));
    text << '\n';
  }
  return text.str();
}

}  // namespace

std::vector<StudyRow> read_study_rows(const std::filesystem::path& file, std::uint64_t* valid_bytes) {
  std::vector<StudyRow> rows;
  std::uint64_t valid = 0;
  std::ifstream in(file, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    if (in.eof()) break;  // no newline after it: a torn write
    try {
      rows.push_back(nlohmann::ordered_json::parse(line));
    } catch (const nlohmann::json::exception&) {
      break;
    }
    valid += line.size() + 1;
  }
  if (valid_bytes) *valid_bytes = valid;
  return rows;
}

void write_study_results(const nlohmann::ordered_json& header, std::vector<StudyRow> rows,
                         const std::filesystem::path& out) {
  std::sort(rows.begin(), rows.end(),
            [](const StudyRow& a, const StudyRow& b) { return a["index"].get<std::size_t>() < b["index"].get<std::size_t>(); });
  nlohmann::ordered_json results = header;
  results["rows"] = rows;
  write_text_file(out / "results.json", results.dump(1) + "\n");
  std::vector<std::size_t> all(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) all[i] = i;
  write_text_file(out / "results.csv", csv(header, rows, all));

  // Pareto fronts: overall, and per value of the group axis.
  std::string pareto;
  const auto front_csv = [&](const std::vector<std::size_t>& members, const std::string& group) {
    std::vector<StudyRow> subset;
    for (std::size_t m : members) subset.push_back(rows[m]);
    std::vector<std::size_t> front;
    for (std::size_t f : pareto_front(subset)) front.push_back(members[f]);
    std::string text = csv(header, rows, front, "front", group);
    return text.substr(text.find('\n') + 1);  // the header line once, below
  };
  pareto = csv(header, rows, {}, "front", "");
  pareto += front_csv(all, "all");
  const std::string group_axis = header.value("group_by", "");
  if (!group_axis.empty()) {
    std::vector<std::string> groups;
    for (const StudyRow& row : rows) {
      const std::string g = cell(row["config"].value(group_axis, nlohmann::ordered_json()));
      if (std::find(groups.begin(), groups.end(), g) == groups.end()) groups.push_back(g);
    }
    for (const std::string& g : groups) {
      std::vector<std::size_t> members;
      for (std::size_t i = 0; i < rows.size(); ++i)
        if (cell(rows[i]["config"].value(group_axis, nlohmann::ordered_json())) == g) members.push_back(i);
      pareto += front_csv(members, group_axis + "=" + g);
    }
  }
  write_text_file(out / "pareto.csv", pareto);
}

std::vector<std::size_t> pareto_front(const std::vector<StudyRow>& rows) {
  const auto metric = [](const StudyRow& row, const char* group, const char* name) {
    if (!row.contains(group) || !row[group].contains(name) || !row[group][name].is_number()) return 0.0;
    return row[group][name].get<double>();
  };
  const auto key = [&](const StudyRow& row) {
    return std::array<double, 3>{metric(row, "timing", "draw_ms_median"), metric(row, "deterministic", "error_p99"),
                                 metric(row, "deterministic", "missed_fraction")};
  };
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto a = key(rows[i]);
    bool dominated = false;
    for (std::size_t j = 0; j < rows.size() && !dominated; ++j) {
      if (i == j) continue;
      const auto b = key(rows[j]);
      const bool no_worse = b[0] <= a[0] && b[1] <= a[1] && b[2] <= a[2];
      const bool better = b[0] < a[0] || b[1] < a[1] || b[2] < a[2];
      dominated = no_worse && better;
    }
    if (!dominated) front.push_back(i);
  }
  return front;
}

}  // namespace qdmr
