// Joining shard reports (docs/architecture.md, Scale): `analyze --shard K/N` analyses every N-th view, any job
// runner spreads the shards, and `merge` joins their folders into one report equal to the
// unsharded run's apart from timings.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/limits.h"

namespace va {

// Reads DIR/report.json of every shard folder, checks that they are shards 1..N of one analysis
// (same format, tool version, scene and view count; no shard twice, none missing, no view twice),
// copies every image the views list into outDir and returns the merged report. False + message
// naming the folder and the fix otherwise. A report nested deeper than maxJsonDepth is refused
// before it is parsed (json::checkDepth).
bool mergeReports(const std::vector<std::string> &shardDirs, const std::string &outDir,
                  nlohmann::ordered_json *merged, std::string *err, uint64_t maxJsonDepth = kDefaultMaxJsonDepth);

// Parses "K/N" (1 <= K <= N <= 100000).
bool parseShard(const std::string &text, int *index, int *count, std::string *err);

}  // namespace va
