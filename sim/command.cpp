#include "sim/command.h"
