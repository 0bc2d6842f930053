/* tools/mpi-wait.c: build/mpi-wait.so, an LD_PRELOAD PMPI shim that measures
 * how long a rank spends inside MPI calls (the collectives of a round, the
 * point-to-point gathers), that is, waiting for the other ranks plus moving
 * the bytes. It changes nothing the program computes. At MPI_Finalize it
 * writes "RANK SECONDS_IN_MPI CALLS SECONDS_INIT_TO_FINALIZE" to
 * $MPI_WAIT_DIR/rank.RANK (nothing when MPI_WAIT_DIR is unset).
 * tools/cluster-sim uses it when it is built (make build/mpi-wait.so). */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double inMpi, startTime;
static long calls;

static double Now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define TIMED(call)            \
  double t0 = Now();           \
  int rc = call;               \
  inMpi += Now() - t0;         \
  ++calls;                     \
  return rc

int MPI_Init(int* argc, char*** argv) {
  int rc = PMPI_Init(argc, argv);
  startTime = Now();
  return rc;
}

int MPI_Init_thread(int* argc, char*** argv, int required, int* provided) {
  int rc = PMPI_Init_thread(argc, argv, required, provided);
  startTime = Now();
  return rc;
}

int MPI_Alltoall(const void* sb, int sc, MPI_Datatype st, void* rb, int rc_, MPI_Datatype rt,
                 MPI_Comm comm) {
  TIMED(PMPI_Alltoall(sb, sc, st, rb, rc_, rt, comm));
}

int MPI_Alltoallv(const void* sb, const int* sc, const int* sd, MPI_Datatype st, void* rb,
                  const int* rc_, const int* rd, MPI_Datatype rt, MPI_Comm comm) {
  TIMED(PMPI_Alltoallv(sb, sc, sd, st, rb, rc_, rd, rt, comm));
}

int MPI_Allgather(const void* sb, int sc, MPI_Datatype st, void* rb, int rc_, MPI_Datatype rt,
                  MPI_Comm comm) {
  TIMED(PMPI_Allgather(sb, sc, st, rb, rc_, rt, comm));
}

int MPI_Allreduce(const void* sb, void* rb, int c, MPI_Datatype t, MPI_Op op, MPI_Comm comm) {
  TIMED(PMPI_Allreduce(sb, rb, c, t, op, comm));
}

int MPI_Send(const void* b, int c, MPI_Datatype t, int to, int tag, MPI_Comm comm) {
  TIMED(PMPI_Send(b, c, t, to, tag, comm));
}

int MPI_Recv(void* b, int c, MPI_Datatype t, int from, int tag, MPI_Comm comm, MPI_Status* s) {
  TIMED(PMPI_Recv(b, c, t, from, tag, comm, s));
}

int MPI_Finalize(void) {
  const char* dir = getenv("MPI_WAIT_DIR");
  if (dir) {
    int rank = 0;
    PMPI_Comm_rank(MPI_COMM_WORLD, &rank);
    char path[4096];
    snprintf(path, sizeof path, "%s/rank.%d", dir, rank);
    FILE* f = fopen(path, "w");
    if (f) {
      fprintf(f, "%d %.6f %ld %.6f\n", rank, inMpi, calls, Now() - startTime);
      fclose(f);
    }
  }
  return PMPI_Finalize();
}
