#include "sim/file_set.h"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace sp {

std::string FileSet::key(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
  return (ec ? std::filesystem::path(path) : absolute).lexically_normal().string();
}

void FileSet::add(const std::string& path, std::string contents) { files_[key(path)] = std::move(contents); }

const std::string* FileSet::find(const std::string& path) const {
  const auto it = files_.find(key(path));
  return it == files_.end() ? nullptr : &it->second;
}

std::optional<std::string> readSourceFile(const std::string& path, const FileSet* files) {
  if (files)
    if (const std::string* held = files->find(path)) return *held;
  if (!sourceFileProblem(path, nullptr).empty()) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream out;
  out << in.rdbuf();
  if (in.bad()) return std::nullopt;
  return out.str();
}

std::string sourceFileProblem(const std::string& path, const FileSet* files) {
  if (files && files->find(path)) return {};
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return "is not a regular file (a folder, device or pipe)";
  if (std::filesystem::file_size(path, ec) > kMaxSourceFileBytes) return "is larger than 64 MiB";
  return {};
}

bool sourceFileExists(const std::string& path, const FileSet* files) {
  if (files && files->find(path)) return true;
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

}  // namespace sp
