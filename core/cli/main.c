/* glint: command-line access to glint's core, for scripting and tests.
 *
 * Every subcommand validates its arguments, prints a clear message on
 * error ("glint fit: --res 3 outside 4..512") and exits non-zero:
 *   1  bad usage or invalid input
 *   2  I/O error
 *   3  numerical failure
 * See `glint help` for the list.  main.c dispatches; each command group
 * has its file (cli.h lists them). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "env.h"
#include "measured.h"
#include "merl.h"

#define GLINT_VERSION "0.1.0"

static void usage(FILE *f)
{
    fputs("glint " GLINT_VERSION ": paint how an object should look; glint finds the BRDF.\n"
          "\n"
          "usage: glint COMMAND [ARGS]\n"
          "  scene create [--mesh sphere|torus|teapot|FILE] [--size N|WxH] [--views ico12|ico20]\n"
          "               [--light-angles LO:HI[:mid]] [--distance D] -o scene.json\n"
          "  scene show scene.json               describe a scene (hash, views, samples)\n"
          "  gbuffer scene.json -o DIR [--view K] G-buffers as OpenEXR (named channels)\n"
          "  paint scene.json --brdf SPEC -o DIR [--scale S|auto] [--format exr|png|hdr]\n"
          "        [--env SPEC [--env-rotation DEG] [--lights K] [--shadows auto|on|off]]\n"
          "                                      paint every view with an analytic BRDF\n"
          "                                      (lambert, phong, blinn, ct, ward; e.g.\n"
          "                                      'ct:rough=0.2,kd=0.5,f0=0.3'; anisotropic\n"
          "                                      'ward:rough=0.1,rough_y=0.35'), or two\n"
          "                                      blended over the texture coordinates:\n"
          "                                      'stripes:freq=8,duty=0.3|BRDF|BRDF'\n"
          "                                      (or checker; soft=W blends the edges),\n"
          "                                      or a measured material: merl:FILE, or\n"
          "                                      sgd:NAME / abc:NAME, a published fit in\n"
          "                                      $GLINT_MEASURED_DIR/" MEASURED_FITS_FILE ";\n"
          "                                      radiance: a white Lambertian facing a light\n"
          "                                      of intensity I reads I (--scale 1); auto\n"
          "                                      makes the brightest pixel 1 (8-bit images)\n"
          "  fit scene.json (--paintings DIR | FILE...) -o MATDIR [fit options]\n"
          "  base-render scene.json -o DIR [--brdf SPEC] [--scale S] [--engine E]\n"
          "                                      the images an artist paints over\n"
          "  render MATDIR --scene scene.json (--view K | --eye X,Y,Z --light X,Y,Z\n"
          "         [--target X,Y,Z] [--fov DEG]) [--intensity I] [--size WxH]\n"
          "         [--engine auto|egl|cpu] -o IMAGE   (auto: EGL if it works, else CPU)\n"
          "  export-shader MATDIR -o DIR         GLSL + factor texture + binding manifest\n"
          "  export-brdf MATDIR -o FILE.brdf     BRDF Explorer's analytic .brdf\n"
          "  export-gltf MATDIR --scene scene.json [--bake-res N] -o FILE.glb\n"
          "                                      the scene's mesh with a glTF metallic-\n"
          "                                      roughness material fitted to MATDIR,\n"
          "                                      N x N textures where it varies (32)\n"
          "  export-mtlx MATDIR --scene scene.json -o FILE.mtlx\n"
          "                                      that fit as a MaterialX standard_surface\n"
          "  export-usda MATDIR --scene scene.json [--no-mesh] -o FILE.usda\n"
          "                                      that fit as a UsdPreviewSurface on the mesh\n",
          f);
    fputs("  export-usdz MATDIR --scene scene.json [--bake-res N] -o FILE.usdz\n"
          "                                      the same in a USDZ package, with the .glb's\n"
          "                                      textures where the material varies\n"
          "  export-mtlx-zip MATDIR --scene scene.json [--bake-res N] -o FILE.zip\n"
          "                                      the MaterialX document in a zip, reading\n"
          "                                      those textures where the material varies\n"
          "  export-merl (MATDIR | --brdf SPEC) -o FILE.binary\n"
          "                                      a material (or an analytic truth) as a MERL\n"
          "                                      table (90x90x180 bins, isotropic; BRDF\n"
          "                                      Explorer, ALTA); paint --brdf merl:FILE\n"
          "                                      paints from such a table (measured data)\n"
          "  eval MATDIR --dirs FILE [-o OUT]    evaluate at direction pairs (and u v)\n"
          "  summary MATDIR                      the material in numbers: base colour,\n"
          "                                      highlight strength and width, albedo,\n"
          "                                      polar plot data (JSON)\n"
          "  export-samples scene.json [--paintings DIR] [--channel C] -o samples.txt\n"
          "  fit-samples samples.txt -o MATDIR [--eval samples.txt [--eval-out F]] [fit options]\n"
          "  fit-gbuffers GBDIR --paintings DIR -o MATDIR [fit options]\n"
          "                                      fit G-buffers and RGB paintings made elsewhere\n"
          "                                      (OpenEXR, named channels N, wi, wo, mask, P, uv)\n"
          "  demo [-o DIR]                       paint the sphere, fit, render new views\n"
          "  methods [--json | --schema NAME]    the fit methods and their parameters\n"
          "  version | help\n"
          "\n",
          f);
    fit_opts_usage(f);
}

/* The command line reads the environment files its user names:
 * "file:PATH" (relative to the working directory). */
static int cli_env_resolver(const char *spec, char *path, size_t len, glint_err *err)
{
    if (strncmp(spec, "file:", 5) || !spec[5])
        return glint_err_set(err, GLINT_ENOTFOUND,
                             "unknown environment '%s': a built-in (%s) or file:PATH", spec,
                             env_builtin_names());
    snprintf(path, len, "%s", spec + 5);
    return 0;
}

/* merl:PATH on the command line: the user's own file */
static int cli_merl_resolver(const char *name, char *path, size_t len, glint_err *err)
{
    if ((size_t)snprintf(path, len, "%s", name) >= len)
        return glint_err_set(err, GLINT_EINVAL, "merl: path too long");
    return 0;
}

/* sgd:NAME and abc:NAME: the fits file of $GLINT_MEASURED_DIR */
static void set_measured_fits(void)
{
    static char path[4096];
    const char *dir = getenv("GLINT_MEASURED_DIR");
    if (dir && dir[0] &&
        (size_t)snprintf(path, sizeof path, "%s/%s", dir, MEASURED_FITS_FILE) < sizeof path)
        measured_set_file(path, NULL);
    else
        measured_set_file(NULL, "set GLINT_MEASURED_DIR to a directory holding "
                                MEASURED_FITS_FILE);
}

int main(int argc, char **argv)
{
    static const struct { const char *name; int (*fn)(int, char **); } cmds[] = {
        {"scene", cmd_scene}, {"gbuffer", cmd_gbuffer}, {"paint", cmd_paint},
        {"fit", cmd_fit}, {"render", cmd_render}, {"eval", cmd_eval}, {"summary", cmd_summary},
        {"export-samples", cmd_export_samples}, {"fit-samples", cmd_fit_samples},
        {"fit-gbuffers", cmd_fit_gbuffers},
        {"demo", cmd_demo}, {"base-render", cmd_base_render},
        {"export-shader", cmd_export_shader}, {"export-merl", cmd_export_merl},
        {"export-brdf", cmd_export_brdf}, {"export-gltf", cmd_export_gltf},
        {"export-mtlx", cmd_export_mtlx}, {"export-usda", cmd_export_usda},
        {"export-usdz", cmd_export_usdz}, {"export-mtlx-zip", cmd_export_mtlx_zip},
        {"methods", cmd_methods}};
    static char name[64];

    env_set_resolver(cli_env_resolver);
    merl_set_resolver(cli_merl_resolver);
    set_measured_fits();

    if (argc < 2 || strcmp(argv[1], "help") == 0 || strcmp(argv[1], "--help") == 0 ||
        strcmp(argv[1], "-h") == 0) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    if (strcmp(argv[1], "version") == 0 || strcmp(argv[1], "--version") == 0) {
        puts("glint " GLINT_VERSION);
        return 0;
    }
    for (unsigned i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        if (strcmp(argv[1], cmds[i].name) == 0) {
            snprintf(name, sizeof name, "glint %s", cmds[i].name);
            cmd_name = name;
            {
                int rc = cmds[i].fn(argc - 1, argv + 1);
                cli_render_close();
                return rc;
            }
        }
    }
    fprintf(stderr, "glint: unknown command '%s' (try 'glint help')\n", argv[1]);
    return 1;
}
