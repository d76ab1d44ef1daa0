// Umbrella header of the gausstrack control-law library.
#pragma once

#include "gausstrack/consistent_state.hpp"
#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/jet.hpp"
#include "gausstrack/model.hpp"
#include "gausstrack/status.hpp"
#include "gausstrack/tracking_controller.hpp"
