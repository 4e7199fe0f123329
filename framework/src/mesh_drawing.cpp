// MeshDrawing's key function: defined once here, in the framework library, so that its typeinfo
// is unique and dynamic_cast<const MeshDrawing*> works across plugins' shared objects.
#include <hapsyn/mesh_drawing.hpp>

namespace hapsyn {

MeshDrawing::~MeshDrawing() = default;

std::vector<std::string> MeshDrawing::mesh_warnings() const { return {}; }

}  // namespace hapsyn
