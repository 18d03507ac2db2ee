#pragma once
// bench's pages: OUT/report.html (Tables I and II, the dynamic table, the plots, a link per
// sequence) and OUT/pages/SEQUENCE.html (`idyvins report` of the sequence's runs side by side).

#include <filesystem>
#include <vector>

#include "bench_sweep.h"

namespace idyvins::app {

/// Writes the suite page and one page per sequence with a finished run. `tables` are bench's
/// markdown tables (table1.md, table2.md, dynamic.md); plots are OUT/plots/*.png, inlined.
/// A sequence whose runs cannot be read gets no page; the suite page says why.
void writeBenchPages(const std::filesystem::path& out, const Sweep& sweep, const std::vector<JobResult>& found,
                     const std::vector<std::string>& tables);

}  // namespace idyvins::app
