/* test_stroke.c: the brush of seed 004 (core/truth/stroke.h): exact weights at
 * known distances, polylines against dabs, HDR and negative colors, scale
 * and erase modes, strokes partly or fully outside the image, the JSON
 * round trip, and invalid strokes refused with messages. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "img.h"
#include "stroke.h"

#define EPS (8 * DBL_EPSILON)
/* stored as float: one float rounding of a value of magnitude ~1 */
#define FTOL (2.0 * FLT_EPSILON)

static json_t *parse(const char *text)
{
    json_error_t e;
    json_t *j = json_loads(text, 0, &e);
    if (!j)
        fprintf(stderr, "  bad test JSON: %s\n", e.text);
    return j;
}

/* Parse one stroke from JSON text (max 100 points). */
static int stroke_parse(const char *text, stroke *s, glint_err *e)
{
    json_t *j = parse(text);
    int rc = stroke_from_json(j, "s", 100, s, e);
    json_decref(j);
    return rc;
}

static int img_fill(img *im, int w, int h, float r, float g, float b)
{
    glint_err e;
    if (img_alloc(im, w, h, 3, &e))
        return -1;
    for (int i = 0; i < w * h; i++) {
        im->px[3 * i] = r;
        im->px[3 * i + 1] = g;
        im->px[3 * i + 2] = b;
    }
    return 0;
}

static const float *px(const img *im, int x, int y)
{
    return im->px + 3 * ((size_t)y * (size_t)im->width + (size_t)x);
}

/* ---- weights and distances ---------------------------------------------- */

TEST(weight_exact_at_known_distances)
{
    stroke s;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":10,\"kappa\":0.5,"
                           "\"opacity\":0.8,\"points\":[[10.5,10.5]]}", &s, &e));
    /* d = 0, 3 (3-4-5 triangle), 5 (exactly D/2: included), just beyond */
    ASSERT_NEAR(stroke_distance(&s, 10.5, 10.5), 0.0, 0.0);
    ASSERT_NEAR(stroke_weight(&s, 10.5, 10.5), 0.8, EPS);
    ASSERT_NEAR(stroke_distance(&s, 10.5 + 3, 10.5), 3.0, EPS);
    ASSERT_NEAR(stroke_weight(&s, 10.5 + 3, 10.5), 0.8 * exp(-1.5), EPS);
    ASSERT_NEAR(stroke_distance(&s, 13.5, 14.5), 5.0, EPS);
    ASSERT_NEAR(stroke_weight(&s, 13.5, 14.5), 0.8 * exp(-2.5), EPS);
    ASSERT_NEAR(stroke_weight(&s, 10.5, 10.5 + 5.0), 0.8 * exp(-2.5), EPS);
    ASSERT(stroke_weight(&s, 10.5, 10.5 + 5.000001) == 0.0);
    stroke_free(&s);

    /* kappa 0: a hard disc of full opacity */
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":4,\"points\":[[0,0]]}", &s, &e));
    ASSERT(s.kappa == 0.0 && s.opacity == 1.0 && s.mode == STROKE_PAINT);
    ASSERT(stroke_weight(&s, 2.0, 0.0) == 1.0);
    ASSERT(stroke_weight(&s, 2.0001, 0.0) == 0.0);
    stroke_free(&s);
}

TEST(distance_to_polyline)
{
    stroke s;
    glint_err e;
    /* an L: (0,0) -> (10,0) -> (10,10) */
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":100,"
                           "\"points\":[[0,0],[10,0],[10,10]]}", &s, &e));
    ASSERT_NEAR(stroke_distance(&s, 5, 3), 3.0, EPS);    /* above the first segment */
    ASSERT_NEAR(stroke_distance(&s, 13, 5), 3.0, EPS);   /* beside the second */
    ASSERT_NEAR(stroke_distance(&s, -3, -4), 5.0, EPS);  /* beyond the first end point */
    ASSERT_NEAR(stroke_distance(&s, 13, 14), 5.0, EPS);  /* beyond the last end point */
    ASSERT_NEAR(stroke_distance(&s, 7, 2), 2.0, EPS);    /* inside the corner: nearest is y=0 */
    stroke_free(&s);

    /* repeated points are a dab, not a division by zero */
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":10,\"points\":[[4,4],[4,4]]}", &s,
                           &e));
    ASSERT_NEAR(stroke_distance(&s, 7, 8), 5.0, EPS);
    stroke_free(&s);
}

/* One coverage per stroke: a polyline covering a pixel twice (there and
 * back, or many points along the path) gives the same weight as once. */
TEST(polyline_is_one_coverage_not_accumulated)
{
    stroke one, many, back;
    img a, b, c;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"color\":[1,0,0],\"diameter\":6,\"kappa\":0.3,\"opacity\":0.5,"
                           "\"points\":[[4,8],[28,8]]}", &one, &e));
    ASSERT_OK(stroke_parse("{\"color\":[1,0,0],\"diameter\":6,\"kappa\":0.3,\"opacity\":0.5,"
                           "\"points\":[[4,8],[10,8],[16,8],[22,8],[28,8]]}", &many, &e));
    ASSERT_OK(stroke_parse("{\"color\":[1,0,0],\"diameter\":6,\"kappa\":0.3,\"opacity\":0.5,"
                           "\"points\":[[4,8],[28,8],[4,8]]}", &back, &e));
    ASSERT_OK(img_fill(&a, 32, 16, 0.2f, 0.2f, 0.2f));
    ASSERT_OK(img_fill(&b, 32, 16, 0.2f, 0.2f, 0.2f));
    ASSERT_OK(img_fill(&c, 32, 16, 0.2f, 0.2f, 0.2f));
    ASSERT_OK(stroke_apply(&one, &a, NULL, NULL, &e));
    ASSERT_OK(stroke_apply(&many, &b, NULL, NULL, &e));
    ASSERT_OK(stroke_apply(&back, &c, NULL, NULL, &e));
    for (int i = 0; i < 32 * 16 * 3; i++) {
        ASSERT(a.px[i] == b.px[i]);
        ASSERT(a.px[i] == c.px[i]);
    }
    /* pixel (15, 7): centre (15.5, 7.5), d = 0.5 from the line y = 8 */
    {
        double w = 0.5 * exp(-0.3 * 0.5);
        ASSERT_NEAR(px(&a, 15, 7)[0], w * 1.0 + (1 - w) * 0.2, FTOL);
        ASSERT_NEAR(px(&a, 15, 7)[1], (1 - w) * 0.2, FTOL);
    }
    /* a dab at each point is not the same as the polyline (gaps between dabs) */
    {
        stroke dab;
        img d;
        ASSERT_OK(stroke_parse("{\"color\":[1,0,0],\"diameter\":6,\"kappa\":0.3,"
                               "\"opacity\":0.5,\"points\":[[4,8]]}", &dab, &e));
        ASSERT_OK(img_fill(&d, 32, 16, 0.2f, 0.2f, 0.2f));
        ASSERT_OK(stroke_apply(&dab, &d, NULL, NULL, &e));
        ASSERT(px(&d, 15, 7)[0] == 0.2f);      /* far from the dab */
        ASSERT(px(&d, 3, 7)[0] == px(&a, 3, 7)[0]); /* nearest the end point: same weight */
        img_free(&d);
        stroke_free(&dab);
    }
    img_free(&a);
    img_free(&b);
    img_free(&c);
    stroke_free(&one);
    stroke_free(&many);
    stroke_free(&back);
}

/* Every pixel against the definition, evaluated directly. */
TEST(apply_matches_definition_everywhere)
{
    stroke s;
    img im, ref;
    stroke_report rep;
    long count = 0;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"color\":[0.9,-0.4,3.5],\"diameter\":9.5,\"kappa\":0.21,"
                           "\"opacity\":0.7,\"points\":[[3.2,4.1],[20.7,9.9],[11.1,30.3],"
                           "[40.0,41.0],[39.5,41.2]]}", &s, &e));
    ASSERT_OK(img_fill(&im, 48, 40, 0.1f, 0.5f, 0.25f));
    ASSERT_OK(img_fill(&ref, 48, 40, 0.1f, 0.5f, 0.25f));
    ASSERT_OK(stroke_apply(&s, &im, NULL, &rep, &e));
    for (int y = 0; y < 40; y++)
        for (int x = 0; x < 48; x++) {
            double w = stroke_weight(&s, x + 0.5, y + 0.5);
            for (int c = 0; c < 3; c++) {
                double old = px(&ref, x, y)[c];
                float want = (float)(w * s.color[c] + (1 - w) * old);
                if (w > 0)
                    ASSERT_MSG(px(&im, x, y)[c] == want, "pixel %d %d ch %d: %.9g vs %.9g", x,
                               y, c, px(&im, x, y)[c], want);
                else
                    ASSERT(px(&im, x, y)[c] == (float)old);
            }
            if (w > 0) {
                count++;
                ASSERT(x >= rep.x0 && x <= rep.x1 && y >= rep.y0 && y <= rep.y1);
            }
        }
    ASSERT_EQ(rep.pixels, count);
    ASSERT(count > 100);
    img_free(&im);
    img_free(&ref);
    stroke_free(&s);
}

/* ---- colors and modes -------------------------------------------------------- */

TEST(hdr_and_negative_colors)
{
    stroke hdr, neg;
    img im;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"color\":[4,2.5,10],\"diameter\":3,\"points\":[[5.5,5.5]]}", &hdr,
                           &e));
    ASSERT_OK(stroke_parse("{\"color\":[-1,-0.5,0],\"diameter\":3,\"opacity\":0.25,"
                           "\"points\":[[5.5,5.5]]}", &neg, &e));
    ASSERT_OK(img_fill(&im, 12, 12, 0.8f, 0.8f, 0.8f));
    ASSERT_OK(stroke_apply(&hdr, &im, NULL, NULL, &e));
    /* kappa 0, opacity 1: the color replaces the pixel, HDR kept */
    ASSERT(px(&im, 5, 5)[0] == 4.0f && px(&im, 5, 5)[1] == 2.5f && px(&im, 5, 5)[2] == 10.0f);
    ASSERT(px(&im, 7, 5)[0] == 0.8f); /* d = 2 > 1.5 */
    ASSERT_OK(stroke_apply(&neg, &im, NULL, NULL, &e));
    /* a negative color pulls the value down (removes a highlight) */
    ASSERT_NEAR(px(&im, 5, 5)[0], 0.25 * -1.0 + 0.75 * 4.0, FTOL * 4);
    ASSERT_NEAR(px(&im, 5, 5)[1], 0.25 * -0.5 + 0.75 * 2.5, FTOL * 4);
    ASSERT_NEAR(px(&im, 5, 5)[2], 0.75 * 10.0, FTOL * 10);
    /* where only the negative stroke reaches, values may go below zero */
    ASSERT_OK(stroke_apply(&neg, &im, NULL, NULL, &e));
    img_free(&im);
    ASSERT_OK(img_fill(&im, 12, 12, 0.0f, 0.0f, 0.0f));
    ASSERT_OK(stroke_apply(&neg, &im, NULL, NULL, &e));
    ASSERT_NEAR(px(&im, 5, 5)[0], -0.25, FTOL);
    img_free(&im);
    stroke_free(&hdr);
    stroke_free(&neg);
}

TEST(scale_mode)
{
    stroke s;
    img im;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"mode\":\"scale\",\"scale\":2.5,\"diameter\":20,\"kappa\":0.1,"
                           "\"points\":[[0,0],[16,0]]}", &s, &e));
    ASSERT(s.mode == STROKE_SCALE && s.scale == 2.5);
    ASSERT_OK(img_fill(&im, 16, 16, 0.4f, 0.0f, -0.2f));
    ASSERT_OK(stroke_apply(&s, &im, NULL, NULL, &e));
    for (int y = 0; y < 16; y++) {
        double d = y + 0.5, w = d <= 10 ? exp(-0.1 * d) : 0.0;
        double f = w * 2.5 + (1 - w);
        ASSERT_NEAR(px(&im, 8, y)[0], f * (double)0.4f, FTOL);
        ASSERT(px(&im, 8, y)[1] == 0.0f); /* black stays black */
        ASSERT_NEAR(px(&im, 8, y)[2], f * (double)-0.2f, FTOL);
    }
    stroke_free(&s);
    /* S = 0 darkens to black at the centre of a hard brush */
    ASSERT_OK(stroke_parse("{\"mode\":\"scale\",\"scale\":0,\"diameter\":2,\"points\":[[3.5,3.5]]}",
                           &s, &e));
    ASSERT_OK(stroke_apply(&s, &im, NULL, NULL, &e));
    ASSERT(px(&im, 3, 3)[0] == 0.0f);
    stroke_free(&s);
    img_free(&im);
}

TEST(erase_brings_back_the_base)
{
    stroke paint, erase, half;
    img base, im;
    glint_err e;
    ASSERT_OK(img_fill(&base, 10, 10, 0.3f, 0.6f, 0.9f));
    base.px[3 * (4 * 10 + 4)] = 0.123f; /* a distinctive base pixel */
    ASSERT_OK(img_alloc(&im, 10, 10, 3, &e));
    memcpy(im.px, base.px, sizeof(float) * 300);
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":30,\"points\":[[5,5]]}", &paint, &e));
    ASSERT_OK(stroke_parse("{\"mode\":\"erase\",\"diameter\":3,\"points\":[[4.5,4.5]]}", &erase,
                           &e));
    ASSERT_OK(stroke_parse("{\"mode\":\"erase\",\"diameter\":3,\"opacity\":0.5,"
                           "\"points\":[[7.5,7.5]]}", &half, &e));
    ASSERT_OK(stroke_apply(&paint, &im, NULL, NULL, &e));
    ASSERT(px(&im, 4, 4)[0] == 1.0f);
    /* erase needs the base */
    ASSERT(stroke_apply(&erase, &im, NULL, NULL, &e) == GLINT_EINVAL);
    ASSERT(strstr(e.msg, "base") != NULL);
    ASSERT_OK(stroke_apply(&erase, &im, &base, NULL, &e));
    ASSERT(px(&im, 4, 4)[0] == 0.123f && px(&im, 4, 4)[2] == 0.9f);
    ASSERT(px(&im, 5, 4)[0] == 0.3f);  /* d = 1 <= 1.5: erased */
    ASSERT(px(&im, 6, 4)[0] == 1.0f);  /* d = 2: still painted */
    ASSERT_OK(stroke_apply(&half, &im, &base, NULL, &e));
    ASSERT_NEAR(px(&im, 7, 7)[1], 0.5 * 0.6 + 0.5 * 1.0, FTOL);
    img_free(&base);
    img_free(&im);
    stroke_free(&paint);
    stroke_free(&erase);
    stroke_free(&half);
}

/* ---- bounds -------------------------------------------------------------------- */

TEST(strokes_partly_or_fully_outside)
{
    stroke part, out, huge;
    img im;
    stroke_report rep;
    glint_err e;
    ASSERT_OK(img_fill(&im, 8, 8, 0, 0, 0));
    /* a line along the left edge, half of the brush outside */
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":2,\"points\":[[0,-50],[0,50]]}", &part,
                           &e));
    ASSERT_OK(stroke_apply(&part, &im, NULL, &rep, &e));
    ASSERT_EQ(rep.pixels, 8);           /* column 0 only: centre x 0.5, d 0.5 <= 1; 1.5 > 1 */
    ASSERT_EQ(rep.x0, 0);
    ASSERT_EQ(rep.x1, 0);
    stroke_free(&part);
    img_free(&im);
    ASSERT_OK(img_fill(&im, 8, 8, 0, 0, 0));
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":4,\"points\":[[0,-50],[0,50]]}", &part,
                           &e));
    ASSERT_OK(stroke_apply(&part, &im, NULL, &rep, &e));
    ASSERT_EQ(rep.pixels, 16); /* centres 0.5 and 1.5 within 2 */
    /* entirely outside: nothing changes */
    ASSERT_OK(stroke_parse("{\"color\":[1,1,1],\"diameter\":4,\"points\":[[-10,-10],[-3,20]]}",
                           &out, &e));
    ASSERT_OK(stroke_apply(&out, &im, NULL, &rep, &e));
    ASSERT_EQ(rep.pixels, 0);
    ASSERT(rep.x1 < rep.x0);
    /* far away, huge coordinates and a huge brush: clipped, no overflow */
    ASSERT_OK(stroke_parse("{\"color\":[0.5,0.5,0.5],\"diameter\":65536,"
                           "\"points\":[[1000000,-1000000],[-1000000,-1000000]]}", &huge, &e));
    ASSERT_OK(stroke_apply(&huge, &im, NULL, &rep, &e));
    ASSERT_EQ(rep.pixels, 0);
    stroke_free(&huge);
    ASSERT_OK(stroke_parse("{\"color\":[0.5,0.5,0.5],\"diameter\":65536,"
                           "\"points\":[[1000000,4],[-1000000,4]]}", &huge, &e));
    ASSERT_OK(stroke_apply(&huge, &im, NULL, &rep, &e));
    ASSERT_EQ(rep.pixels, 64);
    ASSERT(px(&im, 7, 7)[2] == 0.5f);
    stroke_free(&huge);
    stroke_free(&part);
    stroke_free(&out);
    img_free(&im);
}

TEST(overflow_is_reported_not_stored)
{
    stroke s;
    img im;
    glint_err e;
    int rc = 0, i;
    ASSERT_OK(stroke_parse("{\"mode\":\"scale\",\"scale\":1000000,\"diameter\":2,"
                           "\"points\":[[0.5,0.5]]}", &s, &e));
    ASSERT_OK(img_fill(&im, 2, 2, 1, 1, 1));
    for (i = 0; i < 10 && rc == 0; i++)
        rc = stroke_apply(&s, &im, NULL, NULL, &e);
    ASSERT_EQ(rc, GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "float range") != NULL);
    ASSERT(isfinite(px(&im, 0, 0)[0]));
    stroke_free(&s);
    img_free(&im);
}

/* The box stroke_apply_list reports holds every pixel the strokes
 * changed, and is the box of the changed pixels where each stroke's
 * colour differs from the image's everywhere it paints. */
TEST(apply_list_box_holds_every_change)
{
    static const char *const lists[] = {
        "[{\"color\":[1,0,0],\"diameter\":6,\"points\":[[20,10],[40,12]]}]",
        "[{\"color\":[0,1,0],\"diameter\":3,\"points\":[[5,70]]},"
        "{\"color\":[0,0,1],\"diameter\":9,\"opacity\":0.5,\"points\":[[90,30],[95,35]]}]",
        "[{\"mode\":\"scale\",\"scale\":2,\"diameter\":4,\"points\":[[50,50]]},"
        "{\"mode\":\"erase\",\"diameter\":2,\"points\":[[60,1],[61,2]]}]",
        "[{\"color\":[1,1,1],\"diameter\":5,\"points\":[[-30,-30]]}]", /* off the image */
    };
    for (size_t t = 0; t < sizeof lists / sizeof lists[0]; t++) {
        json_t *j = parse(lists[t]);
        stroke_limits lim = {10, 100};
        stroke *list;
        int n, x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
        stroke_report all;
        img im, was, base;
        glint_err e;
        ASSERT_OK(stroke_list_from_json(j, &lim, &list, &n, &e));
        ASSERT_OK(img_fill(&im, 100, 80, 0.25f, 0.25f, 0.25f));
        ASSERT_OK(img_fill(&was, 100, 80, 0.25f, 0.25f, 0.25f));
        ASSERT_OK(img_fill(&base, 100, 80, 0.75f, 0.75f, 0.75f));
        ASSERT_OK(stroke_apply_list(list, n, &im, &base, &all, &e));
        for (int y = 0; y < 80; y++)
            for (int x = 0; x < 100; x++)
                if (memcmp(px(&im, x, y), px(&was, x, y), 3 * sizeof(float))) {
                    x0 = x < x0 ? x : x0;
                    y0 = y < y0 ? y : y0;
                    x1 = x > x1 ? x : x1;
                    y1 = y > y1 ? y : y1;
                }
        if (x1 < 0) { /* nothing changed: an empty box */
            ASSERT(all.pixels == 0 && all.x1 < all.x0 && all.y1 < all.y0);
        } else {
            ASSERT(all.pixels > 0);
            ASSERT(all.x0 == x0 && all.y0 == y0 && all.x1 == x1 && all.y1 == y1);
        }
        ASSERT(t != 3 || x1 < 0);
        stroke_list_free(list, n);
        json_decref(j);
        img_free(&im);
        img_free(&was);
        img_free(&base);
    }
}

TEST(apply_list_in_order)
{
    json_t *j = parse("[{\"color\":[1,0,0],\"diameter\":4,\"points\":[[2,2]]},"
                      "{\"color\":[0,1,0],\"diameter\":4,\"opacity\":0.5,\"points\":[[2,2]]},"
                      "{\"mode\":\"erase\",\"diameter\":1,\"points\":[[0.5,0.5]]}]");
    stroke_limits lim = {10, 10};
    stroke *list;
    int n;
    stroke_report all;
    img im, base;
    glint_err e;
    ASSERT_OK(stroke_list_from_json(j, &lim, &list, &n, &e));
    ASSERT_EQ(n, 3);
    ASSERT_OK(img_fill(&im, 4, 4, 0, 0, 0));
    ASSERT_OK(img_fill(&base, 4, 4, 0.5f, 0.5f, 0.5f));
    ASSERT_OK(stroke_apply_list(list, n, &im, &base, &all, &e));
    ASSERT(px(&im, 1, 1)[0] == 0.5f && px(&im, 1, 1)[1] == 0.5f); /* red, then half green */
    ASSERT(px(&im, 0, 0)[0] == 0.5f && px(&im, 0, 0)[2] == 0.5f); /* erased to the base */
    ASSERT_EQ(all.pixels, 12 + 12 + 1); /* the disc of radius 2 at (2,2) misses the 4 corners */
    /* the box of all three: the whole 4x4 (the discs miss only its corners,
     * so every row and column is touched) */
    ASSERT(all.x0 == 0 && all.y0 == 0 && all.x1 == 3 && all.y1 == 3);
    /* the erase needs the base: the message names the stroke */
    ASSERT(stroke_apply_list(list, n, &im, NULL, NULL, &e) == GLINT_EINVAL);
    ASSERT(strstr(e.msg, "strokes[2]") != NULL);
    stroke_list_free(list, n);
    json_decref(j);
    img_free(&im);
    img_free(&base);
}

/* ---- JSON ------------------------------------------------------------------------ */

TEST(json_round_trip)
{
    stroke a, b;
    json_t *j;
    char *text;
    glint_err e;
    ASSERT_OK(stroke_parse("{\"mode\":\"scale\",\"scale\":0.1,\"color\":[1,2,3],\"diameter\":7.3,"
                           "\"kappa\":0.123456789012345678,\"opacity\":0.3,\"tag\":\"c1-42\","
                           "\"points\":[[0.1,0.2],[1e-9,-3.25]]}", &a, &e));
    j = stroke_to_json(&a);
    ASSERT(j != NULL);
    ASSERT(json_object_get(j, "color") == NULL); /* ignored in scale mode: left out */
    text = json_dumps(j, JSON_REAL_PRECISION(17));
    json_decref(j);
    j = parse(text);
    free(text);
    ASSERT_OK(stroke_from_json(j, "s", 10, &b, &e));
    json_decref(j);
    ASSERT(b.mode == a.mode && b.scale == a.scale && b.diameter == a.diameter &&
           b.kappa == a.kappa && b.opacity == a.opacity && b.npoints == 2);
    for (int i = 0; i < 4; i++)
        ASSERT(a.pts[i] == b.pts[i]);
    ASSERT(strcmp(b.tag, "c1-42") == 0);
    stroke_free(&a);
    stroke_free(&b);
}

/* Each invalid stroke is refused with its code and a message naming the
 * field. */
TEST(invalid_strokes_refused)
{
    static const struct {
        const char *json;
        int code;
        const char *msg;
    } cases[] = {
        {"[]", GLINT_EFORMAT, "expected an object"},
        {"{\"color\":[1,1,1],\"points\":[[0,0]]}", GLINT_EFORMAT, "diameter: missing"},
        {"{\"color\":[1,1,1],\"diameter\":-2,\"points\":[[0,0]]}", GLINT_EINVAL, "diameter"},
        {"{\"color\":[1,1,1],\"diameter\":0,\"points\":[[0,0]]}", GLINT_EINVAL, "diameter"},
        {"{\"color\":[1,1,1],\"diameter\":1e9,\"points\":[[0,0]]}", GLINT_EINVAL, "diameter"},
        {"{\"color\":[1,1,1],\"diameter\":\"5\",\"points\":[[0,0]]}", GLINT_EFORMAT,
         "diameter: expected a number, got a string"},
        {"{\"color\":[1,1],\"diameter\":5,\"points\":[[0,0]]}", GLINT_EFORMAT, "color"},
        {"{\"color\":[1,\"x\",1],\"diameter\":5,\"points\":[[0,0]]}", GLINT_EFORMAT, "color[1]"},
        {"{\"diameter\":5,\"points\":[[0,0]]}", GLINT_EFORMAT, "color: missing"},
        {"{\"mode\":\"scale\",\"diameter\":5,\"points\":[[0,0]]}", GLINT_EFORMAT, "scale: missing"},
        {"{\"mode\":\"scale\",\"scale\":-1,\"diameter\":5,\"points\":[[0,0]]}", GLINT_EINVAL,
         "scale"},
        {"{\"mode\":\"smudge\",\"diameter\":5,\"points\":[[0,0]]}", GLINT_EINVAL, "smudge"},
        {"{\"mode\":3,\"diameter\":5,\"points\":[[0,0]]}", GLINT_EFORMAT, "mode"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"kappa\":-0.1,\"points\":[[0,0]]}", GLINT_EINVAL,
         "kappa"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"opacity\":1.5,\"points\":[[0,0]]}", GLINT_EINVAL,
         "opacity"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[]}", GLINT_EINVAL, "points: empty"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[[0]]}", GLINT_EFORMAT, "points[0]"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[[0,0],[1,null]]}", GLINT_EFORMAT,
         "points[1][1]"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[[0,0],[1,2e7]]}", GLINT_EINVAL,
         "points[1][1]"},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[[0,0]],\"opacty\":1}", GLINT_EFORMAT,
         "unknown key \"opacty\""},
        {"{\"color\":[1,1,1],\"diameter\":5,\"points\":[[0,0]],\"tag\":7}", GLINT_EFORMAT, "tag"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        stroke s;
        glint_err e;
        json_t *j = parse(cases[i].json);
        int rc;
        ASSERT(j != NULL);
        memset(&e, 0, sizeof e);
        rc = stroke_from_json(j, "strokes[0]", 100, &s, &e);
        json_decref(j);
        ASSERT_MSG(rc == cases[i].code, "case %zu (%s): code %d, want %d (%s)", i, cases[i].json,
                   rc, cases[i].code, e.msg);
        ASSERT_MSG(strstr(e.msg, cases[i].msg) != NULL && strstr(e.msg, "strokes[0]") != NULL,
                   "case %zu: message \"%s\" lacks \"%s\"", i, e.msg, cases[i].msg);
        ASSERT(s.pts == NULL);
    }
}

/* NaN and infinity cannot come through JSON text, but C callers can build
 * them: json_real refuses them, so test the C-side checks directly. */
TEST(non_finite_refused)
{
    stroke s;
    img im;
    glint_err e;
    json_t *j = json_pack("{s:[fff], s:f, s:[[ff]]}", "color", 1.0, 1.0, 1.0, "diameter", 5.0,
                          "points", 1.0, 1.0);
    ASSERT_OK(stroke_from_json(j, "s", 10, &s, &e));
    json_decref(j);
    ASSERT_OK(img_fill(&im, 4, 4, 0, 0, 0));
    s.pts[0] = NAN;
    ASSERT(stroke_apply(&s, &im, NULL, NULL, &e) == GLINT_EINVAL);
    ASSERT(strstr(e.msg, "point 0") != NULL);
    s.pts[0] = 1.0;
    s.color[1] = INFINITY;
    ASSERT(stroke_apply(&s, &im, NULL, NULL, &e) == GLINT_EINVAL);
    s.color[1] = 1.0;
    s.diameter = NAN;
    ASSERT(stroke_apply(&s, &im, NULL, NULL, &e) == GLINT_EINVAL);
    s.diameter = -1.0;
    ASSERT(stroke_apply(&s, &im, NULL, NULL, &e) == GLINT_EINVAL);
    ASSERT(strstr(e.msg, "diameter") != NULL);
    for (int i = 0; i < 48; i++)
        ASSERT(im.px[i] == 0.0f); /* nothing applied */
    stroke_free(&s);
    img_free(&im);
}

TEST(limits_refused_with_erange)
{
    char buf[4096];
    json_t *j;
    stroke *list;
    int n, off;
    stroke_limits lim = {2, 5};
    glint_err e;

    j = parse("[{\"color\":[1,1,1],\"diameter\":1,\"points\":[[0,0]]},"
              "{\"color\":[1,1,1],\"diameter\":1,\"points\":[[0,0]]},"
              "{\"color\":[1,1,1],\"diameter\":1,\"points\":[[0,0]]}]");
    ASSERT(stroke_list_from_json(j, &lim, &list, &n, &e) == GLINT_ERANGE);
    ASSERT(strstr(e.msg, "limit of 2 strokes") != NULL);
    ASSERT(list == NULL && n == 0);
    json_decref(j);

    off = snprintf(buf, sizeof buf, "[{\"color\":[1,1,1],\"diameter\":1,\"points\":[");
    for (int i = 0; i < 6; i++)
        off += snprintf(buf + off, sizeof buf - (size_t)off, "%s[%d,0]", i ? "," : "", i);
    snprintf(buf + off, sizeof buf - (size_t)off, "]}]");
    j = parse(buf);
    ASSERT(stroke_list_from_json(j, &lim, &list, &n, &e) == GLINT_ERANGE);
    ASSERT(strstr(e.msg, "strokes[0].points: 6 points") != NULL);
    ASSERT(strstr(e.msg, "limit of 5 points") != NULL);
    json_decref(j);

    j = parse("[]");
    ASSERT(stroke_list_from_json(j, &lim, &list, &n, &e) == GLINT_EINVAL);
    json_decref(j);
    j = parse("{}");
    ASSERT(stroke_list_from_json(j, &lim, &list, &n, &e) == GLINT_EFORMAT);
    json_decref(j);
    /* a bad stroke after good ones: nothing leaks, the message names it */
    j = parse("[{\"color\":[1,1,1],\"diameter\":1,\"points\":[[0,0]]},{\"diameter\":1}]");
    ASSERT(stroke_list_from_json(j, &lim, &list, &n, &e) == GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "strokes[1]") != NULL);
    json_decref(j);
}

/* A long many-point stroke over a large image stays fast (tiles cull the
 * segments), and matches the direct definition at sampled pixels. */
TEST(long_stroke_cost_follows_area)
{
    stroke s;
    img im;
    glint_err e;
    int np = 5000;
    memset(&s, 0, sizeof s);
    s.mode = STROKE_PAINT;
    s.color[0] = s.color[1] = s.color[2] = 1.0;
    s.diameter = 12;
    s.kappa = 0.05;
    s.opacity = 1.0;
    s.npoints = np;
    s.pts = malloc(2 * (size_t)np * sizeof *s.pts);
    ASSERT(s.pts != NULL);
    for (int i = 0; i < np; i++) {
        double t = (double)i / (np - 1);
        s.pts[2 * i] = 20 + 980 * t;
        s.pts[2 * i + 1] = 500 + 400 * sin(12 * t);
    }
    ASSERT_OK(img_fill(&im, 1024, 1024, 0, 0, 0));
    ASSERT_OK(stroke_apply(&s, &im, NULL, NULL, &e));
    for (int y = 0; y < 1024; y += 37)
        for (int x = 0; x < 1024; x += 41) {
            double w = stroke_weight(&s, x + 0.5, y + 0.5);
            ASSERT(px(&im, x, y)[0] == (float)(w * 1.0));
        }
    stroke_free(&s);
    img_free(&im);
}

TEST_LIST {
    TEST_ENTRY(weight_exact_at_known_distances),
    TEST_ENTRY(distance_to_polyline),
    TEST_ENTRY(polyline_is_one_coverage_not_accumulated),
    TEST_ENTRY(apply_matches_definition_everywhere),
    TEST_ENTRY(hdr_and_negative_colors),
    TEST_ENTRY(scale_mode),
    TEST_ENTRY(erase_brings_back_the_base),
    TEST_ENTRY(strokes_partly_or_fully_outside),
    TEST_ENTRY(overflow_is_reported_not_stored),
    TEST_ENTRY(apply_list_in_order),
    TEST_ENTRY(apply_list_box_holds_every_change),
    TEST_ENTRY(json_round_trip),
    TEST_ENTRY(invalid_strokes_refused),
    TEST_ENTRY(non_finite_refused),
    TEST_ENTRY(limits_refused_with_erange),
    TEST_ENTRY(long_stroke_cost_follows_area),
};
TEST_MAIN()
