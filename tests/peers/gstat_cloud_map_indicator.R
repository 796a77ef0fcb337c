#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_cloud_map_indicator_test.cpp: R gstat's variogram cloud,
# variogram map and indicator kriging on the Meuse data R's sp package ships (155 samples; the
# first 300 cells of meuse.grid as targets).
# Usage: Rscript gstat_cloud_map_indicator.R outdir
# Writes to outdir (numbers with 17 significant digits):
#   meuse.csv        x,y,zinc,logzinc           the samples
#   grid.csv         x,y                        the targets
#   cloud.csv        left,right,dist,gamma      variogram(log(zinc) ~ 1, cloud = TRUE, cutoff = 400)
#   cloud_dir.csv    left,right,dist,gamma      the same with alpha = 45, tol.hor = 22.5
#   map.csv          dx,dy,np,gamma             variogram(log(zinc) ~ 1, map = TRUE, cutoff = 1000, width = 100)
#   map_odd.csv      dx,dy,np,gamma             the same with cutoff = 950, width = 125 (an uneven grid)
#   indicator.csv    p1,v1,p2,v2,p3,v3          krige(I(zinc < T) ~ 1) for T = 183, 342, 703 (data values:
#                                               the strict < is tested), each with its own model, global
suppressPackageStartupMessages({ library(sp); library(gstat) })
out <- commandArgs(trailingOnly = TRUE)[1]
data(meuse, package = "sp", envir = environment())
data(meuse.grid, package = "sp", envir = environment())
s <- data.frame(x = meuse$x, y = meuse$y, zinc = meuse$zinc, logzinc = log(meuse$zinc))
g <- data.frame(x = meuse.grid$x, y = meuse.grid$y)[1:300, ]
fmt <- function(v) sprintf("%.17g", v)
put <- function(df, name) {
  df[] <- lapply(df, fmt)
  write.csv(df, file.path(out, name), row.names = FALSE, quote = FALSE)
}
put(s, "meuse.csv")
put(g, "grid.csv")
sp_s <- s
coordinates(sp_s) <- ~x + y
cl <- as.data.frame(variogram(logzinc ~ 1, sp_s, cloud = TRUE, cutoff = 400))
put(data.frame(left = cl$left, right = cl$right, dist = cl$dist, gamma = cl$gamma), "cloud.csv")
cd <- as.data.frame(variogram(logzinc ~ 1, sp_s, cloud = TRUE, cutoff = 400, alpha = 45, tol.hor = 22.5))
put(data.frame(left = cd$left, right = cd$right, dist = cd$dist, gamma = cd$gamma), "cloud_dir.csv")
map_csv <- function(cutoff, width, name) {
  m <- as.data.frame(variogram(logzinc ~ 1, sp_s, map = TRUE, cutoff = cutoff, width = width)$map)
  put(data.frame(dx = m$dx, dy = m$dy, np = m$np.var1, gamma = m$var1), name)
}
map_csv(1000, 100, "map.csv")
map_csv(950, 125, "map_odd.csv")
models <- list(vgm(0.12, "Sph", 700, 0.03), vgm(0.18, "Sph", 900, 0.06), vgm(0.14, "Exp", 300, 0.04))
thresholds <- c(183, 342, 703)
res <- list()
for (k in seq_along(thresholds)) {
  s$ind <- as.numeric(s$zinc < thresholds[k])
  kr <- krige(ind ~ 1, locations = ~x + y, data = s, newdata = g, model = models[[k]], debug.level = 0)
  res[[paste0("p", k)]] <- kr$var1.pred
  res[[paste0("v", k)]] <- kr$var1.var
}
put(as.data.frame(res), "indicator.csv")
