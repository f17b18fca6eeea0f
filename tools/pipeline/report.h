// `cadsynth report`: one self-contained HTML page that shows what a dataset holds. The statistics
// are gathered here from the dataset's JSON files (no image is read but the gallery's few, so a
// report of 100,000 frames takes minutes), written as report data (report_data 1, the schema in
// tools/python/cadsynth/report.py), and turned into the page by that script, which cadsynth
// embeds and runs with a Python that has matplotlib (Debian's python3-matplotlib).
#pragma once

#include <filesystem>
#include <string>

namespace cadsynth {

struct ReportOptions {
  int gallery = 6;         // frames in the gallery, chosen to show the extremes
  int panel_width = 320;   // of each panel of a gallery row
  int sparse_percent = 1;  // an image is nearly empty below this share of object pixels (%)
  std::string python;      // the Python to run; empty: $CADSYNTH_PYTHON, /usr/bin/python3, python3
};

// The report data of the dataset at `root` (JSON text). Throws Error naming a missing or damaged
// file.
std::string ReportData(const std::filesystem::path& root, const ReportOptions& options = {});

// Writes the HTML page of the dataset at `root` to `output` (atomically). Throws Error when the
// dataset cannot be read or Python with matplotlib cannot be run (saying how to install it).
void WriteReport(const std::filesystem::path& root, const std::filesystem::path& output,
                 const ReportOptions& options = {});

// The embedded report.py (generated from tools/python/cadsynth/report.py at build time).
extern const char* const kReportScript;

}  // namespace cadsynth
