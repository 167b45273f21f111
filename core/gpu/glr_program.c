/* glr_program.c: glr's GLSL programs (glr_int.h): compiling and linking,
 * uniform locations, the programs every glr holds, and glr_program_check()
 * (glr.h).  The sources are in glr_shaders.h. */
#include "glr.h"

#include <GLES3/gl3.h>
#include <stdio.h>
#include <string.h>

#include "internal/glr_int.h"
#include "internal/glr_shaders.h"

/* ------------------------------------------------------------------------ */
/* Programs                                                                  */
/* ------------------------------------------------------------------------ */

/* Drop trailing white space and turn newlines into spaces (one-line messages). */
static void glr_trim(char *s)
{
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == '\n' || s[n - 1] == ' ' || s[n - 1] == '\r'))
        s[--n] = '\0';
    for (size_t i = 0; i < n; i++)
        if (s[i] == '\n')
            s[i] = ' ';
}

static GLuint glr_compile(GLenum type, const char *src, char *log, size_t loglen)
{
    GLuint s = glCreateShader(type);
    GLint ok = 0;

    if (!s) {
        snprintf(log, loglen, "glCreateShader failed");
        return 0;
    }
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        GLsizei n = 0;
        glGetShaderInfoLog(s, (GLsizei)loglen, &n, log);
        if (n <= 0)
            snprintf(log, loglen, "(no log)");
        glr_trim(log);
        glDeleteShader(s);
        return 0;
    }
    return s;
}

/* Compile and link; 0 on failure with the log in err (GLINT_EFORMAT). */
GLuint glr_link(const char *vs_src, const char *fs_src, const char *what,
                       glint_err *err)
{
    char log[400];
    GLuint vs, fs, p;
    GLint ok = 0;

    log[0] = '\0';
    vs = glr_compile(GL_VERTEX_SHADER, vs_src, log, sizeof log);
    if (!vs) {
        glint_err_set(err, GLINT_EFORMAT, "%s: vertex shader does not compile: %s", what, log);
        return 0;
    }
    fs = glr_compile(GL_FRAGMENT_SHADER, fs_src, log, sizeof log);
    if (!fs) {
        glDeleteShader(vs);
        glint_err_set(err, GLINT_EFORMAT, "%s: fragment shader does not compile: %s", what,
                      log);
        return 0;
    }
    p = glCreateProgram();
    if (p) {
        glAttachShader(p, vs);
        glAttachShader(p, fs);
        glLinkProgram(p);
        glGetProgramiv(p, GL_LINK_STATUS, &ok);
    }
    /* flagged for deletion; freed with the program */
    glDeleteShader(vs);
    glDeleteShader(fs);
    if (!ok) {
        GLsizei n = 0;
        if (p)
            glGetProgramInfoLog(p, (GLsizei)sizeof log, &n, log);
        if (n <= 0)
            snprintf(log, sizeof log, "(no log)");
        glr_trim(log);
        if (p)
            glDeleteProgram(p);
        glint_err_set(err, GLINT_EFORMAT, "%s: program does not link: %s", what, log);
        return 0;
    }
    return p;
}

void glr_locs_get(GLuint p, glr_locs *l)
{
    l->model = glGetUniformLocation(p, "u_model");
    l->normal_matrix = glGetUniformLocation(p, "u_normal_matrix");
    l->view_proj = glGetUniformLocation(p, "u_view_proj");
    l->eye = glGetUniformLocation(p, "u_eye");
    l->light = glGetUniformLocation(p, "u_light");
    l->light_intensity = glGetUniformLocation(p, "u_light_intensity");
    l->gain = glGetUniformLocation(p, "u_gain");
    l->kind = glGetUniformLocation(p, "u_kind");
    l->kd = glGetUniformLocation(p, "u_kd");
    l->ks = glGetUniformLocation(p, "u_ks");
    l->f0 = glGetUniformLocation(p, "u_f0");
    l->exponent = glGetUniformLocation(p, "u_exponent");
    l->rough = glGetUniformLocation(p, "u_rough");
    l->rough_y = glGetUniformLocation(p, "u_rough_y");
    l->vcol = glGetUniformLocation(p, "u_vcol");
    l->vcol_w = glGetUniformLocation(p, "u_vcol_w");
}

int glr_programs_build(glr *g, glint_err *err)
{
    static const char *const vs[GLR_NPROG] = {GLR_VERT_SRC, GLR_VERT_SRC, GLR_VCOL_VERT_SRC};
    static const char *const fs[GLR_NPROG] = {GLR_GBUF_FRAG_SRC, GLR_BASE_FRAG_SRC,
                                              GLR_VCOL_FRAG_SRC};
    static const char *const names[GLR_NPROG] = {"G-buffer program", "base-render program",
                                                 "vertex-colour program"};
    static const float id4[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    static const float id3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

    for (int i = 0; i < GLR_NPROG; i++) {
        g->prog[i] = glr_link(vs[i], fs[i], names[i], err);
        if (!g->prog[i])
            return err ? err->code : GLINT_EFORMAT;
        g->st.gl_objects++;
        glr_locs_get(g->prog[i], &g->loc[i]);
        /* Constant uniforms, set once: glint's meshes are in world space. */
        glUseProgram(g->prog[i]);
        glUniformMatrix4fv(g->loc[i].model, 1, GL_FALSE, id4);
        glUniformMatrix3fv(g->loc[i].normal_matrix, 1, GL_FALSE, id3);
    }
    glUseProgram(0);
    return glr_gl_check(err, "building the programs");
}

/* ------------------------------------------------------------------------ */
/* Checking a program                                                        */
/* ------------------------------------------------------------------------ */

static int glr_program_check_in(glr *g, const char *vert_src, const char *frag_src,
                                glint_err *err)
{
    GLuint p;
    int rc;

    if (!g || !vert_src || !frag_src)
        return glint_err_set(err, GLINT_EINVAL, "glr_program_check: NULL argument");
    rc = glr_enter(g, err);
    if (rc)
        return rc;
    glr_gl_drain();
    p = glr_link(vert_src, frag_src, "shader check", err);
    if (!p)
        return err ? err->code : GLINT_EFORMAT;
    glDeleteProgram(p);
    return glr_gl_check(err, "checking a program");
}

int glr_program_check(glr *g, const char *vert_src, const char *frag_src, glint_err *err)
{
    int rc = glr_program_check_in(g, vert_src, frag_src, err);
    glr_leave(g);
    return rc;
}
