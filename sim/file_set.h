#pragma once
// Where the loaders read files from: the disk, or a set of files held in
// memory first (MuJoCo's virtual file system idea). Re-simulation rebuilds a
// world from the file contents stored in its session log this way, without
// writing them anywhere.

#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace sp {

/// Files by path, held in memory. Paths are compared as absolute, lexically
/// normal paths (relative ones against the current directory at the call).
/// A plain value; not thread-safe for concurrent writes.
class FileSet {
 public:
  /// Adds `path` with `contents`, replacing any file already there.
  void add(const std::string& path, std::string contents);
  /// The contents of `path`, or null if the set does not hold it.
  const std::string* find(const std::string& path) const;
  size_t size() const { return files_.size(); }

 private:
  static std::string key(const std::string& path);
  std::map<std::string, std::string> files_;
};

/// Reads `path`: from `files` when it holds it, else from the disk (regular
/// files only: a folder or a device is not read). nullopt if neither has it.
/// `files` may be null (the disk alone). Thread-safe for a const FileSet.
std::optional<std::string> readSourceFile(const std::string& path, const FileSet* files);

/// Whether readSourceFile() would find `path`.
bool sourceFileExists(const std::string& path, const FileSet* files);

/// Robot, world, parameter and rules files are read whole: at most this many bytes.
inline constexpr std::uintmax_t kMaxSourceFileBytes = 64u << 20;
/// Why readSourceFile() would not read an existing `path`: "" when it
/// would, else "is not a regular file (a folder, device or pipe)" or "is
/// larger than 64 MiB". A device such as /dev/zero would never end.
std::string sourceFileProblem(const std::string& path, const FileSet* files);

}  // namespace sp
