// Our own checked readers for the simple mesh formats: STL (binary and ASCII), PLY (ASCII and
// binary in either byte order) and OFF. assimp crashed, aborted or looped on damaged files of
// these formats (an index past the vertex count, a truncated body, an element without
// properties); these readers work from bytes in memory, check every count against the bytes that
// remain before reserving anything, check every index, and throw Error naming the origin and, in
// text, the line. Other mesh formats (OBJ, glTF, COLLADA, 3MF) stay with assimp, read in a
// guarded child process (tools/pipeline/guarded_import.h).
#pragma once

#include <string>
#include <string_view>

#include "cad/mesh.h"

namespace cadsynth {

// Whether ParseMeshBytes reads files with this extension (lower case, with the dot).
bool HasCheckedMeshReader(const std::string& extension);

// Positions and triangles (no normals) of the mesh in `bytes`, a file of format `extension`
// (".stl", ".ply" or ".off"); `origin` names it in errors. STL keeps its three corners per facet,
// in file order. PLY and OFF keep the file's indexed vertices, less those no face uses;
// polygons are split into triangles (a quad along the diagonal that keeps both halves facing
// the same way, larger polygons as a fan), and faces of fewer than three corners are skipped.
// Numbers are not checked for being finite here. Throws Error.
Mesh ParseMeshBytes(std::string_view bytes, const std::string& extension,
                    const std::string& origin);

Mesh ParseStl(std::string_view bytes, const std::string& origin);
Mesh ParsePly(std::string_view bytes, const std::string& origin);
Mesh ParseOff(std::string_view bytes, const std::string& origin);

}  // namespace cadsynth
