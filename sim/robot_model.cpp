#include "sim/robot_model.h"
