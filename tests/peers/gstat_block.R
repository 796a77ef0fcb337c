#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_block_test.cpp: block kriging in R gstat on the Meuse data
# that R's sp package ships (meuse: 155 samples; the first 400 cells of meuse.grid as block centres).
# Usage: Rscript gstat_block.R outdir
# Writes to outdir (numbers with 17 significant digits):
#   meuse.csv          x,y,logzinc,sqrtdist   the samples
#   grid.csv           x,y,sqrtdist           the block centres
#   block.csv          pred,var  krige(log(zinc) ~ 1, block = c(40, 40)), Sph + nugget, gstat's default rule
#   block_regular.csv  pred,var  the same with set = list(nblockdiscr = 4): an even 4 x 4 grid
#   block_local.csv    pred,var  block = c(40, 40), nmax = 20
#   block_ked.csv      pred,var  krige(log(zinc) ~ sqrt(dist), block = c(100, 60)), external drift
#   block_uk_local.csv pred,var  krige(log(zinc) ~ x + y, block = c(60, 60), nmax = 30), Exp + nugget
suppressPackageStartupMessages({ library(sp); library(gstat) })
out <- commandArgs(trailingOnly = TRUE)[1]
data(meuse, package = "sp", envir = environment())
data(meuse.grid, package = "sp", envir = environment())
s <- data.frame(x = meuse$x, y = meuse$y, logzinc = log(meuse$zinc), sqrtdist = sqrt(meuse$dist))
g <- data.frame(x = meuse.grid$x, y = meuse.grid$y, sqrtdist = sqrt(meuse.grid$dist))[1:400, ]
fmt <- function(v) sprintf("%.17g", v)
put <- function(df, name) {
  df[] <- lapply(df, fmt)
  write.csv(df, file.path(out, name), row.names = FALSE, quote = FALSE)
}
put(s, "meuse.csv")
put(g, "grid.csv")
sph <- vgm(0.15, "Sph", 800, 0.05)
exp_model <- vgm(0.12, "Exp", 250, 0.04)
kr <- function(formula, model, ...) {
  k <- krige(formula, locations = ~x + y, data = s, newdata = g, model = model, debug.level = 0, ...)
  data.frame(pred = k$var1.pred, var = k$var1.var)
}
put(kr(logzinc ~ 1, sph, block = c(40, 40)), "block.csv")
put(kr(logzinc ~ 1, sph, block = c(40, 40), set = list(nblockdiscr = 4)), "block_regular.csv")
put(kr(logzinc ~ 1, sph, block = c(40, 40), nmax = 20), "block_local.csv")
put(kr(logzinc ~ sqrtdist, sph, block = c(100, 60)), "block_ked.csv")
put(kr(logzinc ~ x + y, exp_model, block = c(60, 60), nmax = 30), "block_uk_local.csv")
