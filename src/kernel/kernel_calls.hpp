#pragma once
// This kernel's KernelCalls (kernel/kernel.hpp): one per ISA, counted by the kernel's own entry points.
#include "core/isa_namespace.hpp"
#include "kernel/kernel.hpp"

namespace qdmr::QDMR_ISA_NAMESPACE {

inline KernelCalls kernel_calls;

}  // namespace qdmr::QDMR_ISA_NAMESPACE
