// The multibody engine's Python submodule (pinbore.core.cpp.mechanism).
#pragma once

#include <nanobind/nanobind.h>

namespace pinbore::mechanism
{
void bind_mechanism(nanobind::module_& parent);
}
