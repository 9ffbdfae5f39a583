// NanoVDB's headers, included with its internal assertions off even in debug builds (the sanitizer build):
// NANOVDB_ASSERT is plain assert, and NanoVDB 10's full checksum of a grid of tiles without leaves asserts on a
// null leaf pointer that it never dereferences. Our own asserts stay on after this header.
#pragma once

// clang-format off
#ifndef NDEBUG
#define NERFPT_NANOVDB_RESTORE_ASSERT
#define NDEBUG
#include <cassert>  // assert.h is meant to be included again: assert follows NDEBUG each time
#endif
#include <iostream>  // first: Debian's nanovdb/util/GridValidator.h uses std::cerr without including it
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridValidator.h>
#include <nanovdb/util/IO.h>
#include <nanovdb/util/OpenToNanoVDB.h>
#include <nanovdb/util/SampleFromVoxels.h>
#ifdef NERFPT_NANOVDB_RESTORE_ASSERT
#undef NDEBUG
#undef NERFPT_NANOVDB_RESTORE_ASSERT
#include <cassert>
#endif
// clang-format on
