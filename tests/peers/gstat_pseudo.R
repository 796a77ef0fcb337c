#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_pseudo_test.cpp: R gstat's pseudo cross-variograms
# (variogram(g, pseudo = TRUE)) and fit.lmc on them.
#
#   Rscript gstat_pseudo.R <out_dir>
#
# Data: gstat's fulmar (fulmar sightings, real counts; 1998 and 1999 surveys never co-located),
# and a SIMULATED set `mixed` whose variable B shares 5 of A's locations (gstat's lag-0 estimate).
# Writes
#   fulmar.csv           x,y,f98,f99 (f98 empty on 1999 rows and f99 on 1998 rows)
#   default.csv          id,np,dist,gamma of variogram(g, pseudo = TRUE) (gstat's default bins)
#   cw.csv               the same with cutoff = 100000, width = 7500 (a cutoff not a multiple of width)
#   fit.csv              id,structure,model,psill,range of fit.lmc(cw, g, vgm(1, "Sph", 60000, 1))
#   mixed.csv, mixed_vario.csv   the SIMULATED set and variogram(g, pseudo = TRUE, cutoff = 60, width = 20)
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 1) stop("usage: gstat_pseudo.R out_dir")
out <- args[1]
fmt <- function(df) {  # every number with 17 significant digits
  for (k in names(df)) if (is.numeric(df[[k]])) df[[k]] <- sprintf("%.17g", df[[k]])
  df
}
vario_csv <- function(v, file) {
  write.csv(fmt(data.frame(id = as.character(v$id), np = v$np, dist = v$dist, gamma = v$gamma)),
            file.path(out, file), row.names = FALSE, quote = FALSE)
}
data(fulmar)
f98 <- fulmar[fulmar$year == 1998, ]
f99 <- fulmar[fulmar$year == 1999, ]
wide <- data.frame(x = c(f98$x, f99$x), y = c(f98$y, f99$y),
                   f98 = c(sprintf("%.17g", f98$fulmar), rep("", nrow(f99))),
                   f99 = c(rep("", nrow(f98)), sprintf("%.17g", f99$fulmar)))
wide$x <- sprintf("%.17g", wide$x)
wide$y <- sprintf("%.17g", wide$y)
write.csv(wide, file.path(out, "fulmar.csv"), row.names = FALSE, quote = FALSE)
coordinates(f98) <- ~x + y
coordinates(f99) <- ~x + y
g <- gstat(NULL, "f98", fulmar ~ 1, f98)
g <- gstat(g, "f99", fulmar ~ 1, f99)
vario_csv(variogram(g, pseudo = TRUE), "default.csv")
cw <- variogram(g, pseudo = TRUE, cutoff = 100000, width = 7500)
vario_csv(cw, "cw.csv")
f <- fit.lmc(cw, g, vgm(1, "Sph", 60000, 1))
rows <- list()
for (id in c("f98", "f99", "f98.f99")) {
  mm <- f$model[[id]]
  rows[[id]] <- data.frame(id = id, structure = seq_len(nrow(mm)) - 1, model = as.character(mm$model),
                           psill = mm$psill, range = mm$range)
}
write.csv(fmt(do.call(rbind, rows)), file.path(out, "fit.csv"), row.names = FALSE, quote = FALSE)

set.seed(2)  # SIMULATED
A <- data.frame(x = runif(20, 0, 100), y = runif(20, 0, 100), z = rnorm(20))
B <- data.frame(x = c(A$x[1:5], runif(15, 0, 100)), y = c(A$y[1:5], runif(15, 0, 100)), z = rnorm(20))
write.csv(data.frame(x = sprintf("%.17g", c(A$x, B$x)), y = sprintf("%.17g", c(A$y, B$y)),
                     a = c(sprintf("%.17g", A$z), rep("", 20)), b = c(rep("", 20), sprintf("%.17g", B$z))),
          file.path(out, "mixed.csv"), row.names = FALSE, quote = FALSE)
coordinates(A) <- ~x + y
coordinates(B) <- ~x + y
g <- gstat(NULL, "a", z ~ 1, A)
g <- gstat(g, "b", z ~ 1, B)
vario_csv(variogram(g, pseudo = TRUE, cutoff = 60, width = 20), "mixed_vario.csv")
