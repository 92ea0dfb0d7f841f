#pragma once
// The files of a study folder besides rows.jsonl: results.json, results.csv and pareto.csv, written from the
// header (study.json) and the rows. Shared by run_study and merge_studies, so a merged study has the same files.
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "qdmr/study/study.hpp"

namespace qdmr {

void write_study_results(const nlohmann::ordered_json& header, std::vector<StudyRow> rows,
                         const std::filesystem::path& out);

// Rows of rows.jsonl; a torn last line (a killed write) is dropped. `valid_bytes` gets the length of the file's
// whole lines, to cut the torn rest before appending.
std::vector<StudyRow> read_study_rows(const std::filesystem::path& file, std::uint64_t* valid_bytes = nullptr);

}  // namespace qdmr
