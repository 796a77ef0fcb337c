#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_variogram_test.cpp: R gstat's empirical variogram and
# fit.variogram on data the test generates.
#
#   Rscript gstat_variogram.R <data.csv> <boundaries "b1,b2,..."> <out_prefix>
#
# data.csv has columns x,y,z,v. Writes
#   <out_prefix>_matheron.csv, <out_prefix>_cressie.csv : np,dist,gamma (gstat's non-empty bins)
#   <out_prefix>_default.csv : the same for variogram(v ~ 1, d) on x, y only, gstat's default bins
#   <out_prefix>_fit.csv : model,method,psill,range,nugget,sserr,singular — fit.variogram of the
#                          Matheron variogram for Sph/Exp/Gau + nugget and fit.method 1, 2, 7.
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 3) stop("usage: gstat_variogram.R data.csv b1,b2,... out_prefix")
d <- read.csv(args[1])
b <- as.numeric(strsplit(args[2], ",")[[1]])
prefix <- args[3]
coordinates(d) <- ~x + y + z
fmt <- function(df) {  # every number with 17 significant digits, no padding
  for (k in names(df)) if (is.numeric(df[[k]])) df[[k]] <- sprintf("%.17g", df[[k]])
  df
}
vm <- variogram(v ~ 1, d, boundaries = b)
write.csv(fmt(data.frame(np = vm$np, dist = vm$dist, gamma = vm$gamma)),
          paste0(prefix, "_matheron.csv"), row.names = FALSE, quote = FALSE)
# gstat's default bins, in 2-D (x, y): cutoff = 0.33333 x the bounding-box diagonal, width = cutoff / 15.
d2 <- read.csv(args[1])
coordinates(d2) <- ~x + y
vd <- variogram(v ~ 1, d2)
write.csv(fmt(data.frame(np = vd$np, dist = vd$dist, gamma = vd$gamma)),
          paste0(prefix, "_default.csv"), row.names = FALSE, quote = FALSE)
vc <- variogram(v ~ 1, d, boundaries = b, cressie = TRUE)
write.csv(fmt(data.frame(np = vc$np, dist = vc$dist, gamma = vc$gamma)),
          paste0(prefix, "_cressie.csv"), row.names = FALSE, quote = FALSE)
rows <- list()
for (m in c("Sph", "Exp", "Gau")) {
  for (method in c(1, 2, 7)) {
    start <- vgm(psill = 0.8 * max(vm$gamma), model = m, range = max(vm$dist) / 3,
                 nugget = 0.5 * min(vm$gamma))
    f <- suppressWarnings(fit.variogram(vm, start, fit.method = method))
    rows[[length(rows) + 1]] <- data.frame(
      model = tolower(m), method = method, psill = f$psill[2], range = f$range[2],
      nugget = f$psill[1], sserr = attr(f, "SSErr"), singular = attr(f, "singular"))
  }
}
write.csv(fmt(do.call(rbind, rows)), paste0(prefix, "_fit.csv"), row.names = FALSE, quote = FALSE)
# Nested models (vgm(..., add.to = ...)), fitted to a variogram whose semivariances follow a known
# nested model nug + sph + sph at the Matheron bins' lags (perturbed by a deterministic +-4 %), so
# that a nested fit is meaningful: every parameter free, and the ranges held (fit.ranges = FALSE),
# for fit.method 1 and 7.
#   <out_prefix>_nested_vario.csv : np,dist,gamma (the variogram fitted)
#   <out_prefix>_nested.csv : case,method,structure,start_psill,start_range,psill,range,sserr
# one row per structure in gstat's row order (the nugget first, its range 0).
truth <- vgm(psill = 0.3, model = "Sph", range = 120,
             add.to = vgm(psill = 0.5, model = "Sph", range = 700, nugget = 0.05))
vn <- vm
vn$gamma <- variogramLine(truth, dist_vector = vm$dist)$gamma * (1 + 0.04 * sin(3 * seq_along(vm$dist)))
write.csv(fmt(data.frame(np = vn$np, dist = vn$dist, gamma = vn$gamma)),
          paste0(prefix, "_nested_vario.csv"), row.names = FALSE, quote = FALSE)
tmpl <- vgm(psill = 0.2, model = "Sph", range = 110,
            add.to = vgm(psill = 0.6, model = "Sph", range = 650, nugget = 0.02))
rows <- list()
for (case in c("free", "fixed_ranges")) {
  for (method in c(1, 7)) {
    f <- suppressWarnings(fit.variogram(vn, tmpl, fit.method = method, fit.ranges = (case == "free")))
    for (k in seq_len(nrow(f))) {
      rows[[length(rows) + 1]] <- data.frame(
        case = case, method = method, structure = k - 1, start_psill = tmpl$psill[k], start_range = tmpl$range[k],
        psill = f$psill[k], range = f$range[k], sserr = attr(f, "SSErr"))
    }
  }
}
write.csv(fmt(do.call(rbind, rows)), paste0(prefix, "_nested.csv"), row.names = FALSE, quote = FALSE)
