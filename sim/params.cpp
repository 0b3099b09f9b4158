#include "sim/params.h"
