/* hf_op.c: regularized pseudo-inverse operator (eq. 6-8) and its parser.
 *
 * With B = U S V^T, the regularized pseudo-inverse applied to g = [f; 0] is
 *   y = sum_i c_i v_i (u_i . g) = sum_i (c_i / s_i) v_i (v_i . A^T f),
 * because u_i . g = (B v_i / s_i) . g = v_i . (B^T g) / s_i and B^T g = A^T f
 * (the Laplacian rows of g are zero).  The analysis vectors u'_i of eq. 9-10
 * are therefore applied implicitly: glint keeps M = V diag(c/s) V^T (n x n)
 * and the sparse rows of A, a few hundred KiB to a few MiB instead of the
 * n x N dense pseudo-inverse. */
#include <cblas.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hf_int.h"

static int parse_rank_part(const char *p, hf_reg *r, int allow_rel, glint_err *err)
{
    char *end;
    double v;

    if (*p == '\0' || strcmp(p, "full") == 0)
        return 0;
    if (allow_rel && strncmp(p, "rel", 3) == 0) {
        v = strtod(p + 3, &end);
        if (end == p + 3 || *end || !isfinite(v) || v <= 0.0 || v >= 1.0)
            return glint_err_set(err, GLINT_EINVAL,
                                 "relative cutoff '%s' must be relT with 0 < T < 1", p);
        r->rel = v;
        return 0;
    }
    v = strtod(p, &end);
    if (end == p || !isfinite(v))
        return glint_err_set(err, GLINT_EINVAL, "rank '%s' is not a number, P%% or 'full'", p);
    if (*end == '%' && end[1] == '\0') {
        if (v <= 0.0 || v > 100.0)
            return glint_err_set(err, GLINT_ERANGE, "rank percentage %g outside (0, 100]", v);
        r->frac = v / 100.0;
        return 0;
    }
    if (*end || v < 1.0 || v > 1e6 || v != floor(v))
        return glint_err_set(err, GLINT_EINVAL, "rank '%s' must be a whole number >= 1", p);
    r->rank = (int)v;
    return 0;
}

int hf_reg_parse(const char *spec, hf_reg *out, glint_err *err)
{
    const char *colon;
    size_t len;

    memset(out, 0, sizeof *out);
    if (!spec)
        return glint_err_set(err, GLINT_EINVAL, "missing regularization");
    colon = strchr(spec, ':');
    len = colon ? (size_t)(colon - spec) : strlen(spec);
    if (len == 5 && strncmp(spec, "trunc", 5) == 0) {
        out->kind = HF_REG_TRUNC;
        return colon ? parse_rank_part(colon + 1, out, 1, err) : 0;
    }
    if (len == 6 && strncmp(spec, "linear", 6) == 0) {
        out->kind = HF_REG_LINEAR;
        return colon ? parse_rank_part(colon + 1, out, 0, err) : 0;
    }
    if (len == 8 && strncmp(spec, "tikhonov", 8) == 0) {
        const char *p = colon ? colon + 1 : "";
        char *end;
        double v;
        int rel = strncmp(p, "rel", 3) == 0;
        out->kind = HF_REG_TIKHONOV;
        if (rel)
            p += 3;
        v = strtod(p, &end);
        if (end == p || *end || !isfinite(v) || v <= 0.0 || v > 1e12)
            return glint_err_set(err, GLINT_EINVAL,
                                 "tikhonov needs a finite alpha > 0 ('tikhonov:0.5' or "
                                 "'tikhonov:rel0.01'), got '%s'", colon ? colon + 1 : "");
        if (rel)
            out->alpha_rel = v;
        else
            out->alpha = v;
        return 0;
    }
    return glint_err_set(err, GLINT_EINVAL,
                         "unknown regularization '%s' (trunc, tikhonov, linear)", spec);
}

void hf_reg_format(const hf_reg *r, char *buf, size_t len)
{
    const char *name = r->kind == HF_REG_TRUNC ? "trunc"
                       : r->kind == HF_REG_LINEAR ? "linear" : "tikhonov";
    if (r->kind == HF_REG_TIKHONOV) {
        if (r->alpha_rel > 0.0)
            snprintf(buf, len, "%s:rel%g", name, r->alpha_rel);
        else
            snprintf(buf, len, "%s:%g", name, r->alpha);
    } else if (r->rank > 0) {
        snprintf(buf, len, "%s:%d", name, r->rank);
    } else if (r->frac > 0.0) {
        snprintf(buf, len, "%s:%g%%", name, 100.0 * r->frac);
    } else if (r->rel > 0.0) {
        snprintf(buf, len, "%s:rel%g", name, r->rel);
    } else {
        snprintf(buf, len, "%s:full", name);
    }
}

static int choose_k(const hf_decomp *dc, const hf_reg *reg)
{
    int k = dc->rank;
    if (reg->rank > 0) {
        k = reg->rank < dc->rank ? reg->rank : dc->rank;
    } else if (reg->frac > 0.0) {
        k = (int)floor(reg->frac * dc->rank + 0.5);
        if (k < 1)
            k = 1;
        if (k > dc->rank)
            k = dc->rank;
    } else if (reg->rel > 0.0) {
        k = 0;
        while (k < dc->rank && dc->s[k] > reg->rel * dc->s[0])
            k++;
        if (k < 1)
            k = 1;
    }
    return k;
}

int hf_op_build(const hf_decomp *dc, const hf_reg *reg, hf_precision prec,
                hf_op *out, glint_err *err)
{
    double t0 = hf_now();
    int n, K, k = 0;
    double *W = NULL, *M = NULL, alpha = 0.0;

    memset(out, 0, sizeof *out);
    if (!dc || !dc->s || dc->rank < 1)
        return glint_err_set(err, GLINT_EINVAL, "operator needs a decomposition of rank >= 1");
    if (prec != HF_F64 && prec != HF_F32)
        return glint_err_set(err, GLINT_EINVAL, "unknown precision %d", (int)prec);
    n = dc->n;
    K = choose_k(dc, reg);
    if (reg->kind == HF_REG_TIKHONOV) {
        alpha = reg->alpha_rel > 0.0 ? reg->alpha_rel * dc->s[0] : reg->alpha;
        if (!isfinite(alpha) || alpha <= 0.0)
            return glint_err_set(err, GLINT_ERANGE, "tikhonov alpha %g must be finite and > 0",
                                 alpha);
        K = dc->rank;
    }
    W = malloc((size_t)n * K * sizeof *W);
    M = calloc((size_t)n * n, sizeof *M);
    if (!W || !M) {
        free(W);
        free(M);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d operator", n, n);
    }
    out->weight_sum = 0.0;
    for (int i = 0; i < K; i++) {
        double s = dc->s[i], w;
        switch (reg->kind) {
        case HF_REG_TIKHONOV: w = 1.0 / (s * s + alpha * alpha); break;
        case HF_REG_LINEAR: w = (1.0 - (double)i / K) / (s * s); break;
        default: w = 1.0 / (s * s); break;
        }
        if (!(w > 0.0))
            continue;
        /* column k of W = sqrt(w) v_i, so that M = W W^T */
        double sw = sqrt(w);
        for (int r = 0; r < n; r++)
            W[r + (size_t)n * k] = sw * dc->V[r + (size_t)n * i];
        if (k == 0)
            out->s_first = s;
        out->s_last = s;
        out->weight_sum += w;
        k++;
    }
    /* M = W W^T; symmetric, computed in the upper triangle and mirrored.
     * Column-major upper = row-major lower; mirror gives the full matrix. */
    cblas_dsyrk(CblasColMajor, CblasUpper, CblasNoTrans, n, k, 1.0, W, n, 0.0, M, n);
    for (int c = 0; c < n; c++)
        for (int r = c + 1; r < n; r++)
            M[r + (size_t)n * c] = M[c + (size_t)n * r];
    free(W);
    out->res = dc->res;
    out->n = n;
    out->k = k;
    out->prec = prec;
    if (prec == HF_F32) {
        out->Mf = malloc((size_t)n * n * sizeof *out->Mf);
        if (!out->Mf) {
            free(M);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d operator", n, n);
        }
        for (size_t i = 0; i < (size_t)n * n; i++)
            out->Mf[i] = (float)M[i];
        free(M);
    } else {
        out->M = M;
    }
    out->build_seconds = hf_now() - t0;
    return 0;
}

void hf_op_free(hf_op *op)
{
    if (!op)
        return;
    free(op->M);
    free(op->Mf);
    memset(op, 0, sizeof *op);
}

size_t hf_op_bytes(const hf_op *op, const hf_design *d)
{
    size_t el = op->prec == HF_F32 ? sizeof(float) : sizeof(double);
    size_t bytes = (size_t)op->n * op->n * el;
    if (d)
        bytes += (size_t)d->n * 3 * (sizeof(int32_t) + sizeof(double));
    return bytes;
}
