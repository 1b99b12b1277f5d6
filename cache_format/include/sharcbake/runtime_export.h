/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file runtime_export.h
 * @brief SHARCBAKE_RUNTIME_API: the mark on every function and class of the runtime library's
 * public headers (C and C++).
 *
 * The shared library is built with hidden visibility, so only what carries this mark is in its
 * dynamic symbol table: the C API and the C++ API, not the internal helpers (file access, the
 * container reader), which stay free to change. The static library and its consumers define
 * SHARCBAKE_RUNTIME_STATIC (the CMake target sets it), which leaves the mark empty; Windows
 * needs that distinction (dllexport / dllimport), ELF does not.
 */
#ifndef SHARCBAKE_RUNTIME_EXPORT_H
#define SHARCBAKE_RUNTIME_EXPORT_H

#if defined(SHARCBAKE_RUNTIME_STATIC)
#define SHARCBAKE_RUNTIME_API
#elif defined(_WIN32)
#if defined(SHARCBAKE_RUNTIME_BUILDING) /* set while building the shared library */
#define SHARCBAKE_RUNTIME_API __declspec(dllexport)
#else
#define SHARCBAKE_RUNTIME_API __declspec(dllimport)
#endif
#elif defined(__GNUC__)
#define SHARCBAKE_RUNTIME_API __attribute__((visibility("default")))
#else
#define SHARCBAKE_RUNTIME_API
#endif

#endif /* SHARCBAKE_RUNTIME_EXPORT_H */
