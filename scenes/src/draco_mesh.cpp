// SPDX-License-Identifier: Apache-2.0
#include "draco_mesh.h"

#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <new>

namespace sharcbake {

struct DracoMesh::Impl {
    std::unique_ptr<draco::Mesh> mesh;
};

DracoMesh::DracoMesh(const unsigned char* data, size_t size) : impl_(new Impl) {
    try {
        draco::DecoderBuffer buffer;
        buffer.Init(reinterpret_cast<const char*>(data), size);
        draco::Decoder decoder;
        auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
        if (!decoded.ok())
            throw std::runtime_error("Draco could not decode it: " + decoded.status().error_msg_string());
        impl_->mesh = std::move(decoded).value();
        const draco::Mesh& mesh = *impl_->mesh;
        indices_.reserve(size_t(mesh.num_faces()) * 3);
        for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f) {
            const draco::Mesh::Face& face = mesh.face(f);
            for (int c = 0; c < 3; ++c) indices_.push_back(face[c].value());
        }
    } catch (const std::bad_alloc&) {
        delete impl_;
        throw std::runtime_error("Draco data asks for more memory than there is");
    } catch (...) {
        delete impl_;
        throw;
    }
}

DracoMesh::~DracoMesh() { delete impl_; }

size_t DracoMesh::pointCount() const { return impl_->mesh->num_points(); }

int DracoMesh::componentCount(int unique_id) const {
    const draco::PointAttribute* a = unique_id < 0 ? nullptr : impl_->mesh->GetAttributeByUniqueId(uint32_t(unique_id));
    return a ? a->num_components() : 0;
}

namespace {
/// 1 / the largest value of an integer data type (what normalization divides by), 0 for floats.
double integerScale(draco::DataType type) {
    switch (type) {
        case draco::DT_INT8: return 1.0 / std::numeric_limits<int8_t>::max();
        case draco::DT_UINT8: return 1.0 / std::numeric_limits<uint8_t>::max();
        case draco::DT_INT16: return 1.0 / std::numeric_limits<int16_t>::max();
        case draco::DT_UINT16: return 1.0 / std::numeric_limits<uint16_t>::max();
        case draco::DT_INT32: return 1.0 / std::numeric_limits<int32_t>::max();
        case draco::DT_UINT32: return 1.0 / std::numeric_limits<uint32_t>::max();
        default: return 0.0;
    }
}
}  // namespace

std::vector<float> DracoMesh::attribute(int unique_id, int components, bool normalize) const {
    const draco::PointAttribute* a = unique_id < 0 ? nullptr : impl_->mesh->GetAttributeByUniqueId(uint32_t(unique_id));
    if (!a) throw std::runtime_error("the Draco data has no attribute " + std::to_string(unique_id));
    const size_t points = pointCount();
    std::vector<float> out(points * size_t(components), 0.0f);
    // Integers the glTF accessor calls normalized but Draco stored plain are scaled here, as
    // glTF reads them; Draco converts the ones it knows to be normalized itself.
    const double scale = normalize && !a->normalized() ? integerScale(a->data_type()) : 0.0;
    std::vector<double> value(size_t(std::max(components, 1)));
    for (draco::PointIndex p(0); p < uint32_t(points); ++p) {
        if (!a->ConvertValue<double>(a->mapped_index(p), int8_t(components), value.data()))
            throw std::runtime_error("Draco attribute " + std::to_string(unique_id) + " has an unreadable value");
        for (int c = 0; c < components; ++c) {
            const double v = scale > 0.0 ? std::max(value[size_t(c)] * scale, -1.0) : value[size_t(c)];
            out[size_t(p.value()) * size_t(components) + size_t(c)] = float(v);
        }
    }
    return out;
}

}  // namespace sharcbake
