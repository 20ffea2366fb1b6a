# Solves CBF files (the subset timeopt writes: free variables; L=, L+, Q and QR rows) with ECOS,
# the embedded conic solver, from Debian's r-cran-ecosolver, and prints one JSON line per file:
# status, objective, iterations and ECOS's own median run time over --repeat solves (its timer,
# so R's overhead is not counted; it includes ECOS's setup, which every solve redoes).
#   Rscript benchmarks/ecos/ecos_cbf.R [--repeat N] FILE.cbf ...
suppressPackageStartupMessages({ library(ECOSolveR); library(Matrix) })

read_cbf <- function(path) {
  lines <- trimws(readLines(path))
  lines <- lines[nchar(lines) > 0 & !startsWith(lines, "#")]
  i <- 1; n <- 0; m <- 0; sense <- 1; blocks <- NULL; obj <- NULL; acoord <- NULL; bcoord <- NULL
  nums <- function(k) as.numeric(strsplit(lines[k], "[[:space:]]+")[[1]])
  entries <- function(start, count, width) {
    if (count == 0) return(matrix(numeric(0), 0, width))
    matrix(scan(text = lines[start:(start + count - 1)], quiet = TRUE), ncol = width, byrow = TRUE)
  }
  while (i <= length(lines)) {
    key <- lines[i]
    if (key == "VER") { i <- i + 2
    } else if (key == "OBJSENSE") { sense <- if (lines[i + 1] == "MAX") -1 else 1; i <- i + 2
    } else if (key == "VAR") {
      h <- nums(i + 1); n <- h[1]
      for (k in seq_len(h[2])) if (strsplit(lines[i + 1 + k], "[[:space:]]+")[[1]][1] != "F") stop("only free variables")
      i <- i + 2 + h[2]
    } else if (key == "CON") {
      h <- nums(i + 1); m <- h[1]
      parts <- strsplit(lines[i + 1 + seq_len(h[2])], "[[:space:]]+")
      blocks <- data.frame(type = sapply(parts, `[`, 1), dim = as.integer(sapply(parts, `[`, 2)))
      i <- i + 2 + h[2]
    } else if (key %in% c("OBJACOORD", "ACOORD", "BCOORD")) {
      count <- nums(i + 1)[1]; width <- if (key == "ACOORD") 3 else 2
      e <- entries(i + 2, count, width)
      if (key == "OBJACOORD") obj <- e else if (key == "ACOORD") acoord <- e else bcoord <- e
      i <- i + 2 + count
    } else stop(paste("unsupported CBF keyword", key))
  }
  cc <- numeric(n); cc[obj[, 1] + 1] <- sense * obj[, 2]
  A <- sparseMatrix(i = acoord[, 1] + 1, j = acoord[, 2] + 1, x = acoord[, 3], dims = c(m, n))
  b <- numeric(m); b[bcoord[, 1] + 1] <- bcoord[, 2]
  # Rows in ECOS order: equalities (A x = -b), orthant, then cones (G x + s = h with G = -A, h = b).
  start <- cumsum(c(0, blocks$dim))[seq_len(nrow(blocks))]
  rows_of <- function(types) as.integer(unlist(lapply(which(blocks$type %in% types), function(k) start[k] + seq_len(blocks$dim[k]))))
  eq <- rows_of("L="); lp <- rows_of("L+")
  G <- -A[lp, , drop = FALSE]; h <- b[lp]; q <- integer(0)
  for (k in which(blocks$type %in% c("Q", "QR"))) {
    r <- start[k] + seq_len(blocks$dim[k]); Gk <- -A[r, , drop = FALSE]; hk <- b[r]
    if (blocks$type[k] == "QR") {  # 2uv >= |w|^2, u, v >= 0  <=>  ((u+v)/sqrt2, (u-v)/sqrt2, w) in Q
      T <- diag(length(r)); T[1:2, 1:2] <- matrix(c(1, 1, 1, -1), 2) / sqrt(2)
      Gk <- T %*% Gk; hk <- as.vector(T %*% hk)
    }
    G <- rbind(G, Gk); h <- c(h, hk); q <- c(q, length(r))
  }
  list(c = cc, sense = sense, A = if (length(eq)) as(A[eq, , drop = FALSE], "CsparseMatrix") else NULL,
       b = -b[eq], G = as(G, "CsparseMatrix"), h = h, dims = list(l = length(lp), q = q, e = 0L))
}

args <- commandArgs(TRUE); repeats <- 7
if (length(args) >= 2 && args[1] == "--repeat") { repeats <- as.integer(args[2]); args <- args[-(1:2)] }
for (f in args) {
  p <- read_cbf(f); times <- numeric(0)
  for (r in seq_len(repeats)) {
    # Fresh copies every time: ECOS works in place on the arrays it is given (scaling), so reusing
    # them would solve a slightly different problem in each repeat.
    G <- p$G; G@x <- G@x + 0
    A <- p$A; if (!is.null(A)) A@x <- A@x + 0
    s <- ECOS_csolve(c = p$c + 0, G = G, h = p$h + 0, dims = p$dims, A = A, b = p$b + 0)
    times <- c(times, s$timing[["runtime"]])
  }
  cat(sprintf('{"file": "%s", "solver": "ecos", "status": "%s", "objective": %.12g, "iterations": %d, "solve_time_ms": %.4g, "repeat": %d}\n',
              basename(f), s$infostring, p$sense * sum(p$c * s$x), as.integer(s$retcodes[["iter"]]), 1e3 * median(times), repeats))
}
