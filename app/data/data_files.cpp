#include "app/data/data_files.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

namespace sp {
namespace {

namespace fs = std::filesystem;

/// The running executable's path ("" when /proc is not there).
fs::path executable() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe;
}

bool readableFolder(const fs::path& folder) {
  std::error_code ec;
  return fs::is_directory(folder, ec) && ::access(folder.c_str(), R_OK | X_OK) == 0;
}

/// Every folder that would be searched, existing or not (for the message).
std::vector<DataFolder> candidates() {
  if (const char* env = std::getenv("SIMPARTNER_DATA"); env && *env)
    return {{fs::absolute(env).lexically_normal().string(), "$SIMPARTNER_DATA"}};
  std::vector<DataFolder> out;
  const fs::path exe = executable();
  if (!exe.empty()) {
    out.push_back({(exe.parent_path().parent_path() / "share" / "simpartner").lexically_normal().string(), "installed"});
    std::error_code ec;
    // /proc/self/exe is canonical; so is the build folder after this.
    const std::string build = fs::weakly_canonical(SP_BUILD_DIR, ec).string() + "/";
    if (!ec && exe.string().compare(0, build.size(), build) == 0) out.push_back({SP_SOURCE_DIR, "source tree"});
  }
  return out;
}

}  // namespace

std::vector<DataFolder> dataFolders(std::string* error) {
  std::vector<DataFolder> out;
  for (DataFolder& d : candidates()) {
    if (readableFolder(d.path)) out.push_back(std::move(d));
    else if (d.why == "$SIMPARTNER_DATA" && error)
      *error = "$SIMPARTNER_DATA: error: " + d.path + ": " +
               (fs::exists(d.path) ? "not a readable folder" : "no such folder");
  }
  return out;
}

std::string findDataFile(const std::string& path, std::string& error) {
  std::error_code ec;
  if (path.empty() || fs::path(path).is_absolute() || fs::exists(path, ec)) return path;
  std::string folderError;
  const std::vector<DataFolder> folders = dataFolders(&folderError);
  for (const DataFolder& d : folders)
    if (fs::exists(fs::path(d.path) / path, ec)) return (fs::path(d.path) / path).string();
  if (!folderError.empty()) {
    error = path + ": error: not found: " + folderError;
    return {};
  }
  // Every place, also those missing, so a broken install says what it lacks.
  std::string where = "the working directory (" + fs::current_path(ec).string() + ")";
  for (const DataFolder& d : candidates())
    where += ", " + d.path + " (" + d.why + (readableFolder(d.path) ? "" : ", missing") + ")";
  error = path + ": error: not found; looked in " + where;
  return {};
}

std::string dataSubfolder(const std::string& subfolder) {
  std::error_code ec;
  for (const DataFolder& d : dataFolders())
    if (fs::is_directory(fs::path(d.path) / subfolder, ec)) return (fs::path(d.path) / subfolder).string();
  return {};
}

}  // namespace sp
