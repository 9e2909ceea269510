// The contact laws' Python submodule (pinbore.core.cpp.laws).
#pragma once

#include <nanobind/nanobind.h>

namespace pinbore::laws
{
void bind_laws(nanobind::module_& parent);
}
