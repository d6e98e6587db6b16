#include "test_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace afterglow::test {

std::string sharedScene(const std::string& relative) {
  fs::path p = fs::path(AFTERGLOW_SHARED_DIR) / "scenes" / relative;
  return fs::exists(p) ? p.lexically_normal().string() : std::string();
}

std::string tempDir(const std::string& name) {
  fs::path p = fs::path(AFTERGLOW_BINARY_DIR) / "test_tmp" / name;
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CliRun runCli(const std::string& dir, const std::string& args) {
  const std::string out = dir + "/.stdout", err = dir + "/.stderr";
  const std::string command =
      std::string("'") + AFTERGLOW_CLI + "' " + args + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(command.c_str());
  CliRun r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

CliChild::CliChild(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe(fds) != 0) return;
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(AFTERGLOW_CLI));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    execv(AFTERGLOW_CLI, argv.data());
    _exit(127);
  }
  close(fds[1]);
  if (pid < 0) {
    close(fds[0]);
    return;
  }
  pid_ = pid;
  fd_ = fds[0];
}

CliChild::~CliChild() {
  if (pid_ > 0) {
    kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  if (fd_ >= 0) close(fd_);
}

bool CliChild::waitForStderr(const std::string& text) {
  char buffer[256];
  while (err_.find(text) == std::string::npos) {
    const ssize_t got = fd_ >= 0 ? read(fd_, buffer, sizeof(buffer)) : -1;
    if (got <= 0) return false;
    err_.append(buffer, size_t(got));
  }
  return true;
}

int CliChild::interruptAndWait(double* cpuSeconds) {
  if (pid_ <= 0) return -1;
  kill(pid_, SIGINT);
  char buffer[256];
  ssize_t got = 0;
  while (fd_ >= 0 && (got = read(fd_, buffer, sizeof(buffer))) > 0) err_.append(buffer, size_t(got));
  int status = 0;
  struct rusage usage {};
  if (wait4(pid_, &status, 0, &usage) != pid_) status = -1;
  pid_ = -1;
  if (cpuSeconds)
    *cpuSeconds = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                  1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return status;
}

}  // namespace afterglow::test
