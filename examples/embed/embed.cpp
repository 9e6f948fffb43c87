// embed: sdfc as a library. Compiles a scene from a string (and shows what a script error
// looks like as a value), asks it for distances, renders it into a buffer written as a
// binary PPM, writes its mesh, and prints the start of its Shadertoy shader.
//   embed [OUT_DIR]   (default: the working folder)
#include <sdfc/sdfc.hpp>

#include <cstdio>
#include <fstream>
#include <string>

int main(int argc, char** argv) {
    const std::string dir = argc > 1 ? argv[1] : ".";
    std::printf("sdfc %s\n", sdfc::api::version());

    // A script error is a value: file, line, column, message, and the text sdfc prints.
    const sdfc::api::Scene broken = sdfc::api::compile_string("sphere(1;\n", "broken.sdf");
    for (const sdfc::api::Diagnostic& d : broken.diagnostics())
        std::printf("%s at %s:%d:%d: %s\n", d.severity.c_str(), d.file.c_str(), d.line, d.column, d.message.c_str());

    sdfc::api::Options options;
    options.defines = {{"r", "0.8"}};  // as -D r=0.8
    const sdfc::api::Scene scene = sdfc::api::compile_string(
        "let r = 1;\n"
        "camera(position = [0, 1.5, 4], target = [0, 0, 0]);\n"
        "material(color = [0.9, 0.4, 0.2]) smooth_union(0.2) { sphere(r); translate([0.8, 0, 0]) box(0.8); }\n",
        "embed.sdf", options);
    if (!scene.ok()) {
        for (const auto& d : scene.diagnostics()) std::fputs(d.text.c_str(), stderr);
        return 1;
    }

    // Distances on a batch of points (x, y, z in separate arrays).
    const float xs[3] = {0, 2, 0}, ys[3] = {0, 0, 3}, zs[3] = {0, 0, 0};
    float d[3];
    scene.distances(xs, ys, zs, d, 3);
    std::printf("distance at (0,0,0) %.3f, (2,0,0) %.3f, (0,3,0) %.3f\n", d[0], d[1], d[2]);

    // A picture into a buffer, then a file of our own (PPM: no image library needed).
    sdfc::api::RenderSettings rs;
    rs.width = 160, rs.height = 90;
    const sdfc::api::Image img = scene.render(rs);
    const std::vector<std::uint8_t> bytes = img.srgb8();
    std::ofstream ppm(dir + "/embed.ppm", std::ios::binary);
    ppm << "P6\n" << img.width << " " << img.height << "\n255\n";
    ppm.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    std::printf("picture %dx%d, centre pixel %d %d %d\n", img.width, img.height, bytes[(45 * 160 + 80) * 3],
                bytes[(45 * 160 + 80) * 3 + 1], bytes[(45 * 160 + 80) * 3 + 2]);

    // A mesh, in memory and as a file.
    sdfc::api::MeshSettings ms;
    ms.resolution = 48;
    const sdfc::api::Mesh mesh = scene.mesh(ms);
    sdfc::api::write_mesh(mesh, dir + "/embed.stl");
    std::printf("mesh %zu vertices, %zu triangles\n", mesh.positions.size(), mesh.triangles.size());

    // The same scene as a Shadertoy shader.
    const std::string glsl = scene.glsl("shadertoy");
    std::printf("shadertoy shader: %zu bytes, starts \"%s\"\n", glsl.size(), glsl.substr(0, glsl.find('\n')).c_str());

    try {
        (void)broken.render();
    } catch (const sdfc::api::Error& e) {
        std::printf("rendering the broken scene throws: %s", e.what());
    }
    return 0;
}
