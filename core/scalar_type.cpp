#include "core/scalar_type.h"

namespace vdiso {

std::optional<ScalarType> parseScalarType(std::string_view name) {
    for (ScalarType t : {ScalarType::U8, ScalarType::I16, ScalarType::U16, ScalarType::F32})
        if (name == scalarTypeName(t)) return t;
    return std::nullopt;
}

}  // namespace vdiso
