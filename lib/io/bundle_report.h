// What --inspect reports beside a bundle's own contents (lazyboe-build, the Python module's
// inspect()): the files beside it and whether planning uses them.
#pragma once

#include <cstdio>
#include <string>

namespace lazyboe {

// The files beside the bundle at `path`: its k-d tree index and workspace index (used by
// planning, or why not) and any checkpoint journal.
void print_files_beside(const std::string& path, std::FILE* out);

}  // namespace lazyboe
