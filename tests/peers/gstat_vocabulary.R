#!/usr/bin/env Rscript
# Peer reference for tests/peers/gstat_vocabulary_test.cpp: gstat's bins for cutoff/width on lattice
# data (lags exactly on bin boundaries), and gstat's variogram and kriging after averaging
# duplicated locations (what `--duplicates average` stands for).
#
#   Rscript gstat_vocabulary.R <out_dir>
#
# Writes
#   coalash.csv          x,y,coalash (gstat's coalash: integer lattice)
#   coalash_cw.csv       id,np,dist,gamma of variogram(coalash ~ 1, cutoff = 10, width = 1)
#   coalash_c.csv        the same with cutoff = 7.5 (gstat's default width 7.5 / 15)
#   dup.csv              SIMULATED x,y,z with 12 locations measured 2 or 3 times
#   dup_vario.csv        variogram(z ~ 1, cutoff = 60, width = 10) of the location means
#   dup_targets.csv      x,y of 5 targets
#   dup_krige.csv        x,y,pred,var of krige(z ~ 1, means, targets, vgm(1, "Exp", 20, 0.1))
suppressPackageStartupMessages({ library(gstat); library(sp) })
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 1) stop("usage: gstat_vocabulary.R out_dir")
out <- args[1]
fmt <- function(df) {  # every number with 17 significant digits
  for (k in names(df)) if (is.numeric(df[[k]])) df[[k]] <- sprintf("%.17g", df[[k]])
  df
}
put <- function(df, file) write.csv(fmt(df), file.path(out, file), row.names = FALSE, quote = FALSE)
vario <- function(v) data.frame(id = as.character(v$id), np = v$np, dist = v$dist, gamma = v$gamma)
data(coalash)
put(coalash, "coalash.csv")
ca <- coalash
coordinates(ca) <- ~x + y
put(vario(variogram(coalash ~ 1, ca, cutoff = 10, width = 1)), "coalash_cw.csv")
put(vario(variogram(coalash ~ 1, ca, cutoff = 7.5)), "coalash_c.csv")

set.seed(49)  # SIMULATED
n <- 60
d <- data.frame(x = runif(n, 0, 100), y = runif(n, 0, 100))
d$z <- sin(d$x / 20) + cos(d$y / 25) + rnorm(n, 0, 0.2)
rep_rows <- rep(1:12, times = c(2, 1, 2, 1, 2, 1, 2, 1, 2, 1, 2, 1))  # 18 more readings at 12 locations
extra <- d[rep_rows, ]
extra$z <- extra$z + rnorm(nrow(extra), 0, 0.3)
all <- rbind(d, extra)
all <- all[sample(nrow(all)), ]  # duplicates anywhere in the file
put(all, "dup.csv")
means <- aggregate(z ~ x + y, data = all, FUN = mean)  # gstat users' remedy for duplicates
coordinates(means) <- ~x + y
put(vario(variogram(z ~ 1, means, cutoff = 60, width = 10)), "dup_vario.csv")
targets <- data.frame(x = c(10, 30.5, 50, 72, 95), y = c(15, 80, 50.5, 22, 90))
put(targets, "dup_targets.csv")
tg <- targets
coordinates(tg) <- ~x + y
k <- krige(z ~ 1, means, tg, vgm(1, "Exp", 20, 0.1), debug.level = 0)
put(data.frame(x = targets$x, y = targets$y, pred = k$var1.pred, var = k$var1.var), "dup_krige.csv")
