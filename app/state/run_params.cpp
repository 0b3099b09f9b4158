#include "app/state/run_params.h"

namespace sp {

std::optional<SimParams> loadRunParams(const std::string& paramsFile, const std::vector<std::string>& overrides,
                                       Diagnostics& diag) {
  SimParams params;
  bool ok = paramsFile.empty() || loadParams(paramsFile, params, diag);
  for (const std::string& o : overrides) ok = applyOverride(params, o, diag) && ok;
  if (!ok) return std::nullopt;
  return params;
}

}  // namespace sp
