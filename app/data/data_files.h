#pragma once
// Where SimPartner finds the files it ships with: robots/, terrains/,
// config/ and docs/, together "the data folder". The console and the tools
// name them relative to it (`terrains/flat.world.xml`), so they start from
// any working directory, installed or not.
//
// The data folders, in order:
//   1. $SIMPARTNER_DATA when it is set, and then only it (a folder asked for
//      by name that is missing is an error, not a reason to look elsewhere);
//   2. the installed one, `<prefix>/share/simpartner` beside the running
//      executable's `<prefix>/bin` (a relocated install still finds its own);
//   3. the source tree, only while the executable runs from the build tree
//      it was built in (an installed copy never reads the checkout).
//
// Plain C++ (no Qt): the headless tools use it too. Thread-safe.

#include <string>
#include <vector>

namespace sp {

/// A folder searched for shipped files, and why it is searched.
struct DataFolder {
  std::string path;  ///< absolute
  std::string why;   ///< "$SIMPARTNER_DATA", "installed", "source tree"
};

/// The data folders that exist, in search order. With $SIMPARTNER_DATA set
/// to a folder that is missing or unreadable: none, and `error` says so.
std::vector<DataFolder> dataFolders(std::string* error = nullptr);

/// Resolves a file the user or a default named: an absolute path, or one
/// that exists from the working directory, is taken as it is; otherwise
/// the first data folder holding it. Returns "" with `error` naming every
/// place it looked (`terrains/x.world.xml: error: not found; looked in ...`)
/// when none has it.
std::string findDataFile(const std::string& path, std::string& error);

/// The first data folder holding `subfolder` (e.g. "robots"), for file
/// dialogs to start in; "" when none does.
std::string dataSubfolder(const std::string& subfolder);

}  // namespace sp
