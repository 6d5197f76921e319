// A bundle file's bytes (HDF5, schemas/bundle.md), opened by one of the paths a tool opens one
// with (chosen by the input's first byte):
// read_bundle (lazyboe-build --inspect/--resume, lazyboe-perturb), the header alone,
// BundleView::open memory-mapped and read into memory (lazyboe-query, lazyboe-bench) and the
// checksum pass of --verify. Each runs the one bundle validation (bundle_check.h); what it
// accepts must then be safe to use, so every edge's command profile is evaluated as the
// simulator evaluates it.
#include <vector>

#include "fuzz_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/common/error.h"
#include "lazyboe/sim/command_profile.h"

using namespace lazyboe;

namespace {
void use_view(const BundleView& view) {
  std::vector<double> v(view.dof()), a(view.dof()), offset(view.dof());
  double sum = 0;
  for (size_t e = 0; e < view.size(); ++e) {
    const CommandProfile profile = view.command(e);
    for (double t : {0.0, 0.5 * profile.duration, profile.duration})
      evaluate_command(profile, t, v.data(), a.data(), offset.data());
    sum += view.q0(e)[0] + view.qf(e)[view.dof() - 1] + view.duration(e) + v[0];
    if (view.has_perturbation()) sum += view.p_lazy_prop(e) + view.p_collision(e);
    if (view.has_transfer()) sum += view.p_lazy_prop_transfer(e) + view.transfer_max_error(e);
  }
  volatile double keep = sum;  // the reads must happen
  (void)keep;
}

template <typename F>
void refused_or_fine(F&& open) {
  try {
    open();
  } catch (const Error&) {
    // Refused with a message: expected. Anything else is a finding.
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The first byte chooses the reader, the rest is the file: one HDF5 open per execution (five
  // would make the target five times slower; every reader still gets a fifth of the inputs).
  if (size == 0) return 0;
  const std::string path = fuzz::write_scratch("bundle.h5", data + 1, size - 1);
  switch (data[0] % 5) {
    case 0:
      refused_or_fine([&] { (void)read_bundle(path); });
      break;
    case 1:
      refused_or_fine([&] { (void)read_bundle_header(path); });
      break;
    case 2:
      refused_or_fine([&] { use_view(BundleView::open(path, true)); });
      break;
    case 3:
      refused_or_fine([&] { use_view(BundleView::open(path, false)); });
      break;
    default:
      refused_or_fine([&] { (void)verify_bundle_checksums(path); });
  }
  return 0;
}
