// Report outputs: report.json (docs/report-schema.json) and the per-view images.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "analysis/results.h"

namespace va {

constexpr const char *kReportFormat = "visaudit-report/1";

// The whole report as JSON (ordered keys, deterministic: no timestamps outside "ms" fields).
nlohmann::ordered_json reportJson(const AnalysisResult &result);

// Writes NAME.depth.exr, NAME.depth.png, NAME.overdraw.png and NAME.ids.exr for one view into dir.
bool writeViewImages(const ViewResult &view, const std::string &dir, std::string *err);

// Writes a text file atomically (temporary name in the same folder, then rename).
bool writeFileAtomic(const std::string &path, const std::string &contents, std::string *err);

// An output directory written as a whole or not at all: files go into a staging folder next to
// the target, and commit() swaps it in. An existing target is replaced only if it is a visaudit
// report folder (holds report.json) or empty; anything else is refused, never deleted.
class OutputDir {
  public:
    bool open(const std::string &target, std::string *err);
    const std::string &staging() const { return staging_; }
    bool commit(std::string *err);
    ~OutputDir();  // removes the staging folder unless committed

  private:
    std::string target_, staging_;
    bool committed_ = false;
};

}  // namespace va
