/* api_core.c: health and metrics. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "admit.h"
#include "app.h"
#include "fitsvc.h"

static http_resp healthz(http_req *req)
{
    app *a = req->app;
    return http_json(200, json_pack("{s:s, s:I}", "status", "ok", "uptime_s",
                                    (json_int_t)(time(NULL) - a->started)));
}

static http_resp metrics(http_req *req)
{
    app *a = req->app;
    http_stats st;
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    static const char *cls[6] = {"", "1xx", "2xx", "3xx", "4xx", "5xx"};
    uint64_t cum = 0;

    if (!f)
        return http_problem(500, NULL, "cannot build metrics");
    http_stats_get(a->http, &st);
    fprintf(f, "# HELP glintd_requests_total HTTP requests answered, by status class.\n");
    fprintf(f, "# TYPE glintd_requests_total counter\n");
    for (int i = 1; i < 6; i++)
        fprintf(f, "glintd_requests_total{class=\"%s\"} %llu\n", cls[i],
                (unsigned long long)st.by_class[i]);
    fprintf(f, "# HELP glintd_request_duration_seconds Time to answer a request.\n");
    fprintf(f, "# TYPE glintd_request_duration_seconds histogram\n");
    for (int i = 0; i < 12; i++) {
        cum = st.latency_bucket[i];
        fprintf(f, "glintd_request_duration_seconds_bucket{le=\"%g\"} %llu\n",
                http_latency_bounds[i], (unsigned long long)cum);
    }
    fprintf(f, "glintd_request_duration_seconds_bucket{le=\"+Inf\"} %llu\n",
            (unsigned long long)st.requests);
    fprintf(f, "glintd_request_duration_seconds_sum %.6f\n", st.latency_sum);
    fprintf(f, "glintd_request_duration_seconds_count %llu\n", (unsigned long long)st.requests);
    fprintf(f, "# HELP glintd_uptime_seconds Seconds since start.\n# TYPE glintd_uptime_seconds gauge\n");
    fprintf(f, "glintd_uptime_seconds %lld\n", (long long)(time(NULL) - a->started));
    fitsvc_metrics(a->fits, f);
    admit_metrics(a->work, f);
    fclose(f);
    return http_bytes_owned(200, "text/plain; version=0.0.4; charset=utf-8", buf, len);
}

const http_route api_core_routes[] = {
    {"GET", "/healthz", healthz},
    {"GET", "/metrics", metrics},
    {"GET", "/api/v1/healthz", healthz},
};
const int api_core_nroutes = sizeof api_core_routes / sizeof api_core_routes[0];
