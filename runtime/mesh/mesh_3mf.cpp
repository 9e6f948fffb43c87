// 3MF through lib3mf (Debian's lib3mf-dev, the 1.x C interface): one mesh object, one build
// item, a colour per triangle corner from the mesh's vertex colours. Written to memory and
// handed to the checked writer like every other output; read back for the tests.
#include "runtime/mesh/mesh_3mf.hpp"

#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include <Model/COM/NMR_DLLInterfaces.h>

#include "runtime/mesh/mesh_file.hpp"

namespace sdfc::mesh {
namespace {

using namespace NMR;

// Releases a lib3mf object at the end of its scope.
struct Held {  // lib3mf's handles are PLib3MFBase pointers
    PLib3MFBase* p = nullptr;
    ~Held() {
        if (p) lib3mf_release(p);
    }
};

void check(LIB3MFRESULT r, PLib3MFBase* on, const char* what) {
    if (r == LIB3MF_OK) return;
    DWORD code = 0;
    LPCSTR msg = nullptr;
    if (on) lib3mf_getlasterror(on, &code, &msg);
    throw std::runtime_error(fmt::format("3MF: {} failed ({})", what, msg && *msg ? msg : fmt::format("error {:#x}", unsigned(r))));
}

}  // namespace

std::string encode_3mf(const Mesh& m) {
    Held model;
    check(lib3mf_createmodel(&model.p), nullptr, "creating the model");
    Held object;
    check(lib3mf_model_addmeshobject(model.p, &object.p), model.p, "adding the mesh");
    check(lib3mf_object_setnameutf8(object.p, "sdfc"), object.p, "naming the mesh");
    std::vector<MODELMESHVERTEX> v(m.positions.size());
    for (size_t i = 0; i < v.size(); ++i)
        for (int k = 0; k < 3; ++k) v[i].m_fPosition[k] = m.positions[i][k];
    std::vector<MODELMESHTRIANGLE> t(m.triangles.size());
    for (size_t i = 0; i < t.size(); ++i)
        for (int k = 0; k < 3; ++k) t[i].m_nIndices[k] = m.triangles[i][size_t(k)];
    // (An empty mesh stays an object with no vertices: lib3mf refuses empty arrays' null data.)
    if (!t.empty())
        check(lib3mf_meshobject_setgeometry(object.p, v.data(), DWORD(v.size()), t.data(), DWORD(t.size())), object.p,
              "setting the geometry");
    if (m.colors.size() == m.positions.size() && !m.colors.empty()) {
        Held props;
        check(lib3mf_meshobject_createpropertyhandler(object.p, &props.p), object.p, "adding colours");
        std::vector<MODELMESH_TRIANGLECOLOR_SRGB> c(t.size());
        for (size_t i = 0; i < t.size(); ++i)
            for (int k = 0; k < 3; ++k) {
                const glm::vec3& col = m.colors[m.triangles[i][size_t(k)]];
                c[i].m_Colors[k] = {srgb_byte(col.x), srgb_byte(col.y), srgb_byte(col.z), 255};
            }
        check(lib3mf_propertyhandler_setgradientcolorarray(props.p, c.data()), props.p, "setting colours");
        Held def;  // 3MF wants an object colour too: the first vertex's
        check(lib3mf_object_createdefaultpropertyhandler(object.p, &def.p), object.p, "adding the object colour");
        const MODELMESHCOLOR_SRGB& c0 = c.empty() ? MODELMESHCOLOR_SRGB{204, 204, 204, 255} : c[0].m_Colors[0];
        check(lib3mf_defaultpropertyhandler_setcolorrgb(def.p, c0.m_Red, c0.m_Green, c0.m_Blue), def.p, "setting the object colour");
    }
    Held item;
    check(lib3mf_model_addbuilditem(model.p, object.p, nullptr, &item.p), model.p, "adding the build item");
    Held writer;
    check(lib3mf_model_querywriter(model.p, "3mf", &writer.p), model.p, "making the writer");
    ULONG64 size = 0;
    check(lib3mf_writer_getstreamsize(writer.p, &size), writer.p, "sizing the file");
    std::string bytes(size_t(size), '\0');
    check(lib3mf_writer_writetobuffer(writer.p, reinterpret_cast<BYTE*>(bytes.data()), size), writer.p, "writing the file");
    return bytes;
}

Mesh decode_3mf(const std::string& bytes) {
    Held model;
    check(lib3mf_createmodel(&model.p), nullptr, "creating the model");
    Held reader;
    check(lib3mf_model_queryreader(model.p, "3mf", &reader.p), model.p, "making the reader");
    std::string copy = bytes;
    check(lib3mf_reader_readfrombuffer(reader.p, reinterpret_cast<BYTE*>(copy.data()), copy.size()), reader.p, "reading");
    Held it;
    check(lib3mf_model_getmeshobjects(model.p, &it.p), model.p, "listing the meshes");
    Mesh out;
    BOOL more = false;
    check(lib3mf_resourceiterator_movenext(it.p, &more), it.p, "listing the meshes");
    while (more) {
        Held res;
        check(lib3mf_resourceiterator_getcurrent(it.p, &res.p), it.p, "reading a mesh");
        DWORD nv = 0, nt = 0;
        check(lib3mf_meshobject_getvertexcount(res.p, &nv), res.p, "counting vertices");
        check(lib3mf_meshobject_gettrianglecount(res.p, &nt), res.p, "counting triangles");
        std::vector<MODELMESHVERTEX> v(nv);
        std::vector<MODELMESHTRIANGLE> t(nt);
        if (nv) check(lib3mf_meshobject_getvertices(res.p, v.data(), nv, nullptr), res.p, "reading vertices");
        if (nt) check(lib3mf_meshobject_gettriangleindices(res.p, t.data(), nt, nullptr), res.p, "reading triangles");
        const uint32_t base = uint32_t(out.positions.size());
        for (const auto& x : v) out.positions.emplace_back(x.m_fPosition[0], x.m_fPosition[1], x.m_fPosition[2]);
        for (const auto& x : t) out.triangles.push_back({base + x.m_nIndices[0], base + x.m_nIndices[1], base + x.m_nIndices[2]});
        check(lib3mf_resourceiterator_movenext(it.p, &more), it.p, "listing the meshes");
    }
    return out;
}

}  // namespace sdfc::mesh
