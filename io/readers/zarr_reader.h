// Zarr volumes from a directory store: a plain Zarr v2 or v3 array, or an OME-Zarr image
// (v0.4 on Zarr v2, v0.5 on Zarr v3) read at one level of its multiscales.
//
// The path is the array's folder (.zarray or zarr.json with node_type "array") or the image's
// group folder (.zattrs, or zarr.json with attributes.ome). For OME-Zarr, `level` picks
// multiscales[0].datasets[level] (0, the finest, by default); spacing and origin come from that
// dataset's "scale" and "translation" coordinate transformations, then the multiscale's own,
// on the three spatial axes (units are not converted). A plain array has spacing 1.
// The array's last three axes are z, y, x; any axes before them (OME-Zarr's t and c) must have
// size 1. Chunk formats: io/readers/zarr_array.h.
//
// Missing chunks are the fill value, as the Zarr specification says; a chunk that cannot be
// decoded is an error naming its file. Streaming: one layer of chunks (the chunk depth in z,
// across the whole slice) is decoded at a time, so memory is that layer whatever the depth; at
// a URL, the next layer's stored chunks are fetched meanwhile, and held too.
#pragma once

#include <memory>
#include <string>

#include "io/remote/remote_options.h"
#include "io/readers/slice_reader.h"

namespace vdiso {

// Throws IoError naming the store (and the chunk, for chunk errors) on any problem; for a level
// out of range, the message lists the levels and their shapes.
// `path` may be a URL (https://, http://, s3://: io/readers/zarr_keys.h), reached with `remote`.
std::unique_ptr<SliceReader> openZarrVolume(const std::string& path, int level,
                                            const RemoteOptions& remote = {});

// True if `dir` holds Zarr metadata (.zarray, .zgroup, .zattrs or zarr.json).
bool looksLikeZarr(const std::string& dir);

}  // namespace vdiso
