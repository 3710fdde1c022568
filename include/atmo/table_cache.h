// The table cache: a folder where models keep the tables their precomputation makes, so that a
// later process that creates the same model reads them instead of computing them again.
//
// A source4d or elek model's tables depend on the atmosphere and the model's options, never on
// the sun or the observer, and take seconds to compute (source4d at 15 channels: about 2 s of
// wall time on 2 cores, docs/performance.md); read back, a tenth of that or less. CreateModel looks
// a model up by a key made of the model's name, its options, the atmosphere's canonical JSON and
// BuildId(): the tables read back are bit-identical to the ones this build would compute.
//
//   atmo::SetTableCache(atmo::DefaultTableCache());   // what the atmo command does
//   auto model = atmo::CreateModel("source4d", atmo::Preset("us-standard"));   // computed, then kept
//   auto again = atmo::CreateModel("source4d", atmo::Preset("us-standard"));   // read back
//
// The library reads the tables shipped with atmo and keeps nothing new until SetTableCache is
// called. Files are written whole (a temporary file, then a rename), each holds its whole key and
// a checksum, and one that is truncated, corrupt, of another key or unreadable is ignored (the
// tables are computed again and the file replaced).
// A folder that cannot be written costs only the saving: CreateModel never fails because of the
// cache. The least recently used files are removed when the folder grows past max_bytes.
// docs/cli.md, "The table cache".
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace atmo {

struct TableCache {
  // Where new tables are kept (and looked for first); empty: none are kept.
  std::filesystem::path folder;
  std::uint64_t max_bytes = std::uint64_t{1} << 30;  // 1 GiB
  // Folders only read, after `folder`: ShippedTableFolders() by default.
  std::vector<std::filesystem::path> shipped;
};

// The tables made when atmo was built: share/atmo/tables of its build tree and of its install
// prefix, where they exist. They hold the default sky (source4d on us-standard, the default
// options), so that the first `atmo render` reads its tables (docs/cli.md, "The table cache").
std::vector<std::filesystem::path> ShippedTableFolders();

// The process's cache (thread-safe). Until SetTableCache is called it reads the shipped tables
// and keeps nothing (TableCache{"", 1 GiB, ShippedTableFolders()}); std::nullopt turns it off,
// shipped tables included.
void SetTableCache(std::optional<TableCache> cache);
std::optional<TableCache> GetTableCache();

// The cache the atmo command uses: the shipped folders, and a folder that keeps tables:
// $ATMO_TABLE_CACHE when it is set ("off" or an empty value: none; otherwise a folder), else
// $XDG_CACHE_HOME/atmo/tables, else $HOME/.cache/atmo/tables (none when neither is set).
TableCache DefaultTableCache();

// This build's identity in the cache's keys: a hash of the library's sources, the compiler and
// its flags, made when the library is built (any change to the code that computes tables makes
// earlier files stale).
std::string_view BuildId();

}  // namespace atmo
