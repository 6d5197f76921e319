#include "lazyboe/io/bundle_report.h"

#include <filesystem>
#include <vector>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/checkpoint_journal.h"
#include "lazyboe/planning/edge_index_file.h"
#include "lazyboe/planning/workspace_index.h"

namespace lazyboe {

void print_files_beside(const std::string& path, std::FILE* out) {
  std::vector<std::string> lines;
  if (read_bundle_header(path).complete) {
    const BundleView bundle = BundleView::open(path);
    lines.push_back("k-d tree index: " + bundle_index_status(bundle));
    lines.push_back("workspace index: " + workspace_index_status(bundle));
  }
  for (const std::string& journal : {build_journal_path(path), perturb_journal_path(path)}) {
    std::error_code error;
    const uintmax_t bytes = std::filesystem::file_size(journal, error);
    if (!error)
      lines.push_back("checkpoint journal " + journal + ": " + std::to_string(bytes) +
                      " bytes (a run was interrupted; resuming applies it)");
  }
  if (!lines.empty()) std::fprintf(out, "\nbeside it:\n");
  for (const std::string& line : lines) std::fprintf(out, "  %s\n", line.c_str());
}

}  // namespace lazyboe
