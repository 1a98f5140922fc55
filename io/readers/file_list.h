// The files of an input given as a folder or a glob, in the order a person numbered them.
//
// Scanners and microscopes write slices as slice_1.tif ... slice_10.tif, often without zero
// padding, so plain string order would put slice_10 before slice_2. Natural order compares runs
// of digits as numbers (leading zeros ignored, then shorter first), everything else byte by
// byte.
#pragma once

#include <string>
#include <vector>

namespace vdiso {

// True if a sorts before b in natural order ("s2" < "s10" < "s010b").
bool naturalLess(const std::string& a, const std::string& b);

// True if `path` holds a glob metacharacter (*, ? or [): it names files by pattern.
bool isGlobPattern(const std::string& path);

// The regular files directly in `dir` whose names end with one of `suffixes` (ignoring ASCII
// case; every file when `suffixes` is empty), hidden files skipped, in natural order of their
// names. Throws IoError naming the folder if it cannot be read.
std::vector<std::string> listFolder(const std::string& dir, const std::vector<std::string>& suffixes);

// The regular files matching the glob `pattern`, in natural order. Throws IoError naming the
// pattern if none match.
std::vector<std::string> expandGlob(const std::string& pattern);

}  // namespace vdiso
