// The headers most tests include, parsed once per group of tests that are
// compiled alike (tests/CMakeLists.txt, sp_add_test): <QTest> alone costs
// ~5 s of parsing per file, most of a small test's compile.
#pragma once

#include <QProcess>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTest>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>
