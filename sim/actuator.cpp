#include "sim/actuator.h"
