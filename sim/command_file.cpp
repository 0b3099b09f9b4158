#include "sim/command_file.h"
