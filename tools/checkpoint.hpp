// Checkpoints: the exact bytes of every checkpointed particle field plus the caller's state
// (time, step, body states, writer positions...), so that a resumed run is bit-identical to one
// that never stopped. Which fields are saved comes from the field registry (FieldDesc::checkpoint).
//
// Layout of a checkpoint directory:
//   checkpoint.json   {"format":"turbid-checkpoint","version":2,"byte_order":"little","count":N,
//                      "fields":[{"name","type","components","unit","file","bytes","fnv1a64"}...],
//                      "state":<caller's json>,
//                      "digests":{"state","fields"}}   FNV-1a of the state block and of the field
//                      list as written: an edit afterwards (even with a recomputed field checksum)
//                      is refused, naming the block (version 1 files, without digests, still read)
//   <field>.bin       count * components * sizeof(type) raw native (little-endian) bytes
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

#include "sph/particle_store.hpp"

namespace turbid::tools {

// Writes the checkpoint into `dir.tmp` (a sibling of `dir`, removed first if left over), flushes
// it to disk, then replaces `dir`: rename dir -> dir.old, dir.tmp -> dir, delete dir.old. At every
// instant either `dir` or `dir.old` holds a complete checkpoint. The parent directory is created
// if missing. Field names must be usable as file names ([A-Za-z0-9_.-], not starting with '.').
void write_checkpoint(const std::filesystem::path& dir, const sph::ParticleStore& store, const nlohmann::json& state);

// Restores a checkpoint into `store`, which must already have the same fields registered (same
// names, types and components; extra fields that are not checkpointed are allowed). Resizes the
// store to the saved count, fills every checkpointed field bit for bit and zeroes the fields that
// are not checkpointed (passes recompute them). Returns the saved state.
// If `dir` is missing but `dir.old` holds a checkpoint (a crash between the two renames), reads it.
// Throws std::runtime_error naming the file and the field on any mismatch: unreadable or invalid
// checkpoint.json, a field missing on either side, wrong type or components, a field file of the
// wrong size (truncated), a checksum mismatch. Sizes and types are all checked before the store is
// touched; after a checksum error the store's contents are unspecified.
nlohmann::json read_checkpoint(const std::filesystem::path& dir, sph::ParticleStore& store);

// Only the caller's state saved with a checkpoint (same dir.old fallback and errors), e.g. to
// rebuild the run before its particles are restored.
nlohmann::json read_checkpoint_state(const std::filesystem::path& dir);

}  // namespace turbid::tools
