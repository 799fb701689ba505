// SPDX-License-Identifier: GPL-3.0-or-later
#include "synthesis/vulkan/runtime.h"

#include "core/error.h"

#include <vulkan/vulkan.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>

namespace texfab::synthesis::vulkan {

namespace {

// A Vulkan structure with its type set and every other field zero (value-initialized, so that
// -Wmissing-field-initializers stays quiet).
template <class T> T make(VkStructureType type) {
  T t{};
  t.sType = type;
  return t;
}

std::string versionString(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
         std::to_string(VK_API_VERSION_PATCH(v));
}

std::string mib(uint64_t bytes) { return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB"; }

bool validationRequested() {
  const char* v = std::getenv("TEXFAB_VULKAN_VALIDATION");
  return v && *v && std::string(v) != "0";
}

// Messages of the validation layer, kept until the next check turns them into an Error.
struct Messages {
  std::mutex mutex;
  std::vector<std::string> list;
};

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto& m = *static_cast<Messages*>(user);
  std::string text = data && data->pMessage ? data->pMessage : "(no message)";
  std::replace(text.begin(), text.end(), '\n', ' ');
  const std::lock_guard lock(m.mutex);
  m.list.push_back(std::move(text));
  return VK_FALSE;
}

// The instance, with the Khronos validation layer and a messenger when $TEXFAB_VULKAN_VALIDATION
// is set.
struct Instance {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  std::unique_ptr<Messages> messages = std::make_unique<Messages>();

  Instance() {
    const bool validation = validationRequested();
    auto app = make<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
    app.pApplicationName = "texfab";
    app.apiVersion = VK_API_VERSION_1_1;
    auto info = make<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
    info.pApplicationInfo = &app;
    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    auto messengerInfo = make<VkDebugUtilsMessengerCreateInfoEXT>(VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT);
    messengerInfo.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messengerInfo.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messengerInfo.pfnUserCallback = onMessage;
    messengerInfo.pUserData = messages.get();
    const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
    auto features = make<VkValidationFeaturesEXT>(VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT);
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = &sync;
    if (validation) {
      info.enabledLayerCount = 1;
      info.ppEnabledLayerNames = &layer;
      info.enabledExtensionCount = 1;
      info.ppEnabledExtensionNames = &extension;
      features.pNext = &messengerInfo;
      info.pNext = &features;
    }
    const VkResult r = vkCreateInstance(&info, nullptr, &instance);
    if (r == VK_ERROR_LAYER_NOT_PRESENT)
      throw Error("Vulkan validation was requested ($TEXFAB_VULKAN_VALIDATION) but the Khronos validation layer is "
                  "not installed");
    if (r != VK_SUCCESS) throw Error("no Vulkan driver (vkCreateInstance: VkResult " + std::to_string(r) + ")");
    if (validation) {
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkCreateDebugUtilsMessengerEXT"));
      if (create) create(instance, &messengerInfo, nullptr, &messenger);
    }
  }
  ~Instance() {
    if (messenger) {
      auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
      if (destroy) destroy(instance, messenger, nullptr);
    }
    if (instance) vkDestroyInstance(instance, nullptr);
  }
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;

  std::vector<VkPhysicalDevice> physicalDevices() const {
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(instance, &n, nullptr);
    std::vector<VkPhysicalDevice> devices(n);
    vkEnumeratePhysicalDevices(instance, &n, devices.data());
    devices.resize(n);
    return devices;
  }

  // Throws the first validation message, if any.
  void checkMessages() const {
    const std::lock_guard lock(messages->mutex);
    if (messages->list.empty()) return;
    const std::string first = messages->list.front();
    const size_t more = messages->list.size() - 1;
    messages->list.clear();
    throw Error("Vulkan validation: " + first + (more ? " (and " + std::to_string(more) + " more)" : ""));
  }
};

const char* typeName(VkPhysicalDeviceType t) {
  switch (t) {
  case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
  case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
  case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
  case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
  default: return "other";
  }
}

// Lower is preferred when no index is asked for.
int typeRank(VkPhysicalDeviceType t) {
  switch (t) {
  case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
  case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
  case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
  case VK_PHYSICAL_DEVICE_TYPE_CPU: return 4;
  default: return 3;
  }
}

bool hasExtension(VkPhysicalDevice pd, const char* name) {
  uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> extensions(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, extensions.data());
  return std::any_of(extensions.begin(), extensions.begin() + n,
                     [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

// The first queue family with compute, or -1.
int computeFamily(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, families.data());
  for (uint32_t i = 0; i < n; ++i)
    if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return int(i);
  return -1;
}

DeviceInfo describe(VkPhysicalDevice pd, int index) {
  auto driver = make<VkPhysicalDeviceDriverProperties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES);
  auto properties = make<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
  VkPhysicalDeviceProperties& p = properties.properties;
  vkGetPhysicalDeviceProperties(pd, &p);
  const bool v12 = p.apiVersion >= VK_API_VERSION_1_2;
  if (v12) {
    properties.pNext = &driver;
    vkGetPhysicalDeviceProperties2(pd, &properties);
  }
  DeviceInfo info;
  info.index = index;
  info.name = p.deviceName;
  info.type = typeName(p.deviceType);
  info.apiVersion = versionString(p.apiVersion);
  info.driver = v12 ? std::string(driver.driverName) + ", " + driver.driverInfo : "driver " + std::to_string(p.driverVersion);
  info.maxRangeBytes = p.limits.maxStorageBufferRange;
  VkPhysicalDeviceMemoryProperties memory;
  vkGetPhysicalDeviceMemoryProperties(pd, &memory);
  for (uint32_t h = 0; h < memory.memoryHeapCount; ++h)
    if (memory.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      info.memoryBytes = std::max<uint64_t>(info.memoryBytes, memory.memoryHeaps[h].size);
  VkPhysicalDeviceFeatures features;
  vkGetPhysicalDeviceFeatures(pd, &features);
  if (p.apiVersion < VK_API_VERSION_1_1) info.unusable = "Vulkan 1.1 is required";
  else if (!features.shaderInt64) info.unusable = "no shaderInt64";
  else if (!hasExtension(pd, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME)) info.unusable = "no VK_KHR_push_descriptor";
  else if (computeFamily(pd) < 0) info.unusable = "no compute queue";
  return info;
}

// $TEXFAB_VULKAN_DEVICE, or -1.
int deviceFromEnvironment() {
  const char* v = std::getenv("TEXFAB_VULKAN_DEVICE");
  if (!v || !*v) return -1;
  char* end = nullptr;
  const long index = std::strtol(v, &end, 10);
  if (*end || index < 0 || index > 1000)
    throw Error("TEXFAB_VULKAN_DEVICE: expected a device index (0, 1, ...), got '" + std::string(v) + "'");
  return int(index);
}

// $TEXFAB_VULKAN_MAX_RANGE: a lower binding range (bytes), to exercise the splitting of large data.
uint64_t maxRangeFromEnvironment() {
  const char* v = std::getenv("TEXFAB_VULKAN_MAX_RANGE");
  return v && *v ? std::strtoull(v, nullptr, 10) : 0;
}

// The device to open: `index`, else the environment's, else the best usable one.
int chooseDevice(const std::vector<DeviceInfo>& infos, const std::vector<VkPhysicalDeviceType>& types, int index) {
  if (index < 0) index = deviceFromEnvironment();
  if (infos.empty()) throw Error(index < 0 ? "no Vulkan device found" : "no Vulkan device found (device " + std::to_string(index) + " asked for)");
  if (index >= int(infos.size()))
    throw Error("Vulkan device " + std::to_string(index) + " does not exist (" + std::to_string(infos.size()) +
                " found; texfab info --devices lists them)");
  if (index >= 0) {
    if (!infos[size_t(index)].unusable.empty())
      throw Error("Vulkan device " + std::to_string(index) + " (" + infos[size_t(index)].name +
                  ") cannot run texfab: " + infos[size_t(index)].unusable);
    return index;
  }
  int best = -1;
  for (size_t i = 0; i < infos.size(); ++i)
    if (infos[i].unusable.empty() && (best < 0 || typeRank(types[i]) < typeRank(types[size_t(best)]))) best = int(i);
  if (best < 0) throw Error("no usable Vulkan device (" + infos[0].name + ": " + infos[0].unusable + ")");
  return best;
}

// A buffer with its own memory allocation, of `capacity` bytes (a size class, see allocate()).
struct Allocation {
  VkDevice device = VK_NULL_HANDLE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  void* mapped = nullptr;
  uint64_t capacity = 0;
  bool host = false;

  Allocation() = default;
  Allocation(const Allocation&) = delete;
  Allocation& operator=(const Allocation&) = delete;
  ~Allocation() {
    if (buffer) vkDestroyBuffer(device, buffer, nullptr);
    if (memory) vkFreeMemory(device, memory, nullptr);
  }
};

} // namespace

// ---- Device ----

struct Pipeline {
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
};

struct Device::Impl {
  Instance instance;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t family = 0;
  DeviceInfo info;
  VkPhysicalDeviceLimits limits{};
  VkPhysicalDeviceMemoryProperties memory{};
  uint64_t maxRange = 0;
  bool timestamps = false;
  PFN_vkCmdPushDescriptorSetKHR pushDescriptors = nullptr;
  std::mutex mutex;  // pipelines, queue
  std::map<const Kernel*, Pipeline> pipelines;
  std::atomic<bool> lost{false};
  std::atomic<bool> profiling{false};
  std::mutex profileMutex;
  DeviceProfile profile;
  // Allocations released by buffers and staging, kept for reuse (oldest first): creating memory
  // costs far more than the copies of a small request (NVIDIA: ~1 ms per buffer, and every
  // request creates tens of them).
  std::mutex poolMutex;
  std::vector<std::unique_ptr<Allocation>> pool;
  uint64_t pooledBytes = 0;
  uint64_t poolLimit = 0;  // set with the device: min(512 MiB, an eighth of its largest heap)
  // Device::resident's data, most recently used last.
  struct Resident {
    uint64_t key;
    std::shared_ptr<const void> data;
    uint64_t bytes;
  };
  std::mutex residentMutex;
  std::vector<Resident> resident;
  uint64_t residentBytes = 0;

  ~Impl() {
    if (!device) return;
    vkDeviceWaitIdle(device);
    resident.clear();
    pool.clear();
    for (auto& [kernel, p] : pipelines) {
      vkDestroyPipeline(device, p.pipeline, nullptr);
      vkDestroyPipelineLayout(device, p.layout, nullptr);
      vkDestroyDescriptorSetLayout(device, p.setLayout, nullptr);
    }
    vkDestroyDevice(device, nullptr);
  }

  // Throws Error for a failed call; device loss marks the device lost.
  void check(VkResult r, const char* what) {
    if (r == VK_SUCCESS) return;
    if (r == VK_ERROR_DEVICE_LOST) {
      lost = true;
      throw Error("Vulkan device lost: " + info.name);
    }
    if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
      throw Error(std::string("out of ") + (r == VK_ERROR_OUT_OF_DEVICE_MEMORY ? "device" : "host") +
                  " memory on Vulkan device " + info.name + " (" + what + ")");
    throw Error(std::string("Vulkan: ") + what + " failed on " + info.name + " (VkResult " + std::to_string(r) + ")");
  }

  uint32_t memoryType(uint32_t allowed, VkMemoryPropertyFlags wanted, VkMemoryPropertyFlags preferred) const {
    int fallback = -1;
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
      const VkMemoryPropertyFlags f = memory.memoryTypes[i].propertyFlags;
      if (!(allowed & (1u << i)) || (f & wanted) != wanted) continue;
      if ((f & preferred) == preferred) return i;
      if (fallback < 0) fallback = int(i);
    }
    if (fallback < 0) throw Error("Vulkan device " + info.name + " has no suitable memory type");
    return uint32_t(fallback);
  }

  // Sizes are rounded up to classes of at most 1/8 more (and whole 4 KiB), so that released
  // allocations serve later requests of similar sizes.
  static uint64_t sizeClass(uint64_t bytes) {
    const uint64_t step = std::max<uint64_t>(4096, std::bit_ceil(std::max<uint64_t>(bytes, 1)) / 8);
    return (std::max<uint64_t>(bytes, 1) + step - 1) / step * step;
  }

  // A buffer of at least `bytes` (device-local storage, or host-visible and mapped staging): a
  // released one of the same class, else a new one.
  std::unique_ptr<Allocation> allocate(uint64_t bytes, bool host) {
    if (lost) throw Error("Vulkan device lost: " + info.name);
    const uint64_t capacity = sizeClass(bytes);
    {
      const std::lock_guard lock(poolMutex);
      for (auto it = pool.begin(); it != pool.end(); ++it)
        if ((*it)->host == host && (*it)->capacity == capacity) {
          std::unique_ptr<Allocation> a = std::move(*it);
          pool.erase(it);
          pooledBytes -= capacity;
          return a;
        }
    }
    const auto started = std::chrono::steady_clock::now();
    auto a = std::make_unique<Allocation>();
    a->device = device;
    a->capacity = capacity;
    a->host = host;
    auto bi = make<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
    bi.size = capacity;
    bi.usage = host ? VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT
                    : VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                          VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    check(vkCreateBuffer(device, &bi, nullptr, &a->buffer), "vkCreateBuffer");
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(device, a->buffer, &req);
    auto mi = make<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
    mi.allocationSize = req.size;
    mi.memoryTypeIndex =
        host ? memoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                          VK_MEMORY_PROPERTY_HOST_CACHED_BIT)
             : memoryType(req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    const std::string what = "allocating " + mib(bytes);
    check(vkAllocateMemory(device, &mi, nullptr, &a->memory), what.c_str());
    check(vkBindBufferMemory(device, a->buffer, a->memory, 0), "vkBindBufferMemory");
    if (host) check(vkMapMemory(device, a->memory, 0, VK_WHOLE_SIZE, 0, &a->mapped), "vkMapMemory");
    if (profiling) {
      const std::lock_guard lock(profileMutex);
      profile.allocateSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      ++profile.allocations;
    }
    return a;
  }

  // Keeps `a` for reuse, the oldest released ones going first beyond poolLimit.
  void release(std::unique_ptr<Allocation> a) {
    if (!a || lost || a->capacity > poolLimit) return;
    const std::lock_guard lock(poolMutex);
    while (pooledBytes + a->capacity > poolLimit) {
      pooledBytes -= pool.front()->capacity;
      pool.erase(pool.begin());
    }
    pooledBytes += a->capacity;
    pool.push_back(std::move(a));
  }

  const Pipeline& pipeline(const Kernel& kernel);
};

const Pipeline& Device::Impl::pipeline(const Kernel& kernel) {
  const std::lock_guard lock(mutex);
  if (auto it = pipelines.find(&kernel); it != pipelines.end()) return it->second;
  Pipeline p;
  std::vector<VkDescriptorSetLayoutBinding> bindings(kernel.arrays.size());
  for (size_t i = 0; i < bindings.size(); ++i) {
    bindings[i].binding = uint32_t(i);
    bindings[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[i].descriptorCount = kernel.arrays[i];
    bindings[i].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  auto sli = make<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  sli.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  sli.bindingCount = uint32_t(bindings.size());
  sli.pBindings = bindings.data();
  check(vkCreateDescriptorSetLayout(device, &sli, nullptr, &p.setLayout), "vkCreateDescriptorSetLayout");
  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, kernel.paramBytes};
  auto pli = make<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  pli.setLayoutCount = 1;
  pli.pSetLayouts = &p.setLayout;
  pli.pushConstantRangeCount = kernel.paramBytes ? 1 : 0;
  pli.pPushConstantRanges = &push;
  check(vkCreatePipelineLayout(device, &pli, nullptr, &p.layout), "vkCreatePipelineLayout");
  auto smi = make<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  smi.codeSize = kernel.spirv.size_bytes();
  smi.pCode = kernel.spirv.data();
  VkShaderModule module = VK_NULL_HANDLE;
  check(vkCreateShaderModule(device, &smi, nullptr, &module), "vkCreateShaderModule");
  auto cpi = make<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  cpi.stage = make<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
  cpi.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpi.stage.module = module;
  cpi.stage.pName = "main";
  cpi.layout = p.layout;
  const VkResult r = vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &cpi, nullptr, &p.pipeline);
  vkDestroyShaderModule(device, module, nullptr);
  check(r, kernel.name);
  return pipelines.emplace(&kernel, p).first->second;
}

Device::Device(int index, const DeviceOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  const std::vector<VkPhysicalDevice> physical = d.instance.physicalDevices();
  std::vector<DeviceInfo> infos;
  std::vector<VkPhysicalDeviceType> types;
  for (size_t i = 0; i < physical.size(); ++i) {
    infos.push_back(describe(physical[i], int(i)));
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(physical[i], &p);
    types.push_back(p.deviceType);
  }
  const int chosen = chooseDevice(infos, types, index);
  d.physical = physical[size_t(chosen)];
  d.info = infos[size_t(chosen)];
  VkPhysicalDeviceProperties properties;
  vkGetPhysicalDeviceProperties(d.physical, &properties);
  d.limits = properties.limits;
  vkGetPhysicalDeviceMemoryProperties(d.physical, &d.memory);
  d.family = uint32_t(computeFamily(d.physical));
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &n, families.data());
  d.timestamps = families[d.family].timestampValidBits > 0 && d.limits.timestampPeriod > 0;

  const float priority = 1.0f;
  auto qi = make<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
  qi.queueFamilyIndex = d.family;
  qi.queueCount = 1;
  qi.pQueuePriorities = &priority;
  VkPhysicalDeviceFeatures features{};
  features.shaderInt64 = VK_TRUE;
  const char* extension = VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME;
  auto di = make<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
  di.queueCreateInfoCount = 1;
  di.pQueueCreateInfos = &qi;
  di.enabledExtensionCount = 1;
  di.ppEnabledExtensionNames = &extension;
  di.pEnabledFeatures = &features;
  d.check(vkCreateDevice(d.physical, &di, nullptr, &d.device), "vkCreateDevice");
  vkGetDeviceQueue(d.device, d.family, 0, &d.queue);
  d.pushDescriptors =
      reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(vkGetDeviceProcAddr(d.device, "vkCmdPushDescriptorSetKHR"));
  uint64_t range = d.limits.maxStorageBufferRange;
  if (options.maxRangeBytes) range = std::min(range, options.maxRangeBytes);
  d.maxRange = range / 256 * 256;
  d.poolLimit = std::min<uint64_t>(uint64_t(512) << 20, d.info.memoryBytes / 8);
  d.instance.checkMessages();
}

Device::~Device() = default;

const DeviceInfo& Device::info() const { return impl_->info; }
uint64_t Device::maxRangeBytes() const { return impl_->maxRange; }

void Device::setProfiling(bool on) {
  const std::lock_guard lock(impl_->profileMutex);
  impl_->profile = {};
  impl_->profiling = on;
}

DeviceProfile Device::profile() const {
  const std::lock_guard lock(impl_->profileMutex);
  return impl_->profile;
}

std::shared_ptr<const void> Device::residentData(
    uint64_t key, const std::function<std::pair<std::shared_ptr<const void>, uint64_t>()>& make) {
  if (key == 0) return make().first;
  Impl& d = *impl_;
  const std::lock_guard lock(d.residentMutex);  // one maker at a time: a second asker waits for it
  auto& r = d.resident;
  if (auto it = std::find_if(r.begin(), r.end(), [&](const Impl::Resident& e) { return e.key == key; }); it != r.end()) {
    std::rotate(it, it + 1, r.end());
    return r.back().data;
  }
  auto [data, bytes] = make();
  if (bytes > d.poolLimit) return data;
  while (d.residentBytes + bytes > d.poolLimit) {
    d.residentBytes -= r.front().bytes;
    r.erase(r.begin());
  }
  d.residentBytes += bytes;
  r.push_back({key, data, bytes});
  return data;
}

std::shared_ptr<Device> sharedDevice(int index) {
  // The registry is never destroyed: a driver that registered exit handlers of its own when it was
  // loaded (after this registry was built) has torn itself down before static destructors run, and
  // destroying a device then crashes (NVIDIA 580: SIGSEGV at every exit). Process exit frees it.
  static std::mutex mutex;
  static auto& devices = *new std::map<int, std::shared_ptr<Device>>;
  if (index < 0) index = deviceFromEnvironment();
  const std::lock_guard lock(mutex);
  std::shared_ptr<Device>& d = devices[index];
  if (!d || d->impl().lost) d = std::make_shared<Device>(index, DeviceOptions{maxRangeFromEnvironment()});
  return d;
}

bool deviceNamed(int index) { return index >= 0 || deviceFromEnvironment() >= 0; }

std::vector<DeviceInfo> listDevices() {
  try {
    const Instance instance;
    std::vector<DeviceInfo> infos;
    const std::vector<VkPhysicalDevice> devices = instance.physicalDevices();
    for (size_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], int(i)));
    return infos;
  } catch (const Error&) {
    return {};
  }
}

// ---- Buffer ----

struct Buffer::Impl {
  Device::Impl& device;
  std::unique_ptr<Allocation> allocation;
  ~Impl() { device.release(std::move(allocation)); }
};

Buffer::Buffer(Device& device, uint64_t bytes)
    : impl_(new Impl{device.impl(), device.impl().allocate(bytes, false)}), bytes_(bytes) {}
Buffer::Buffer() = default;
Buffer::Buffer(Buffer&&) noexcept = default;
Buffer& Buffer::operator=(Buffer&&) noexcept = default;
Buffer::~Buffer() = default;

// ---- Commands ----

struct Commands::Impl {
  Device::Impl& d;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkQueryPool queries = VK_NULL_HANDLE;
  uint32_t queryCapacity = 0;
  std::vector<const char*> timedKernels;  // kernel name of each pair of timestamps
  std::vector<std::unique_ptr<Allocation>> staging;
  struct Download {
    const Allocation* from;
    uint64_t offset;  // in `from`
    void* to;
    uint64_t bytes;
  };
  std::vector<Download> downloads;
  uint64_t uploadBytes = 0, downloadBytes = 0, dispatches = 0;
  bool recording = false;

  explicit Impl(Device::Impl& device) : d(device) {
    auto pi = make<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
    pi.queueFamilyIndex = d.family;
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    d.check(vkCreateCommandPool(d.device, &pi, nullptr, &pool), "vkCreateCommandPool");
    auto ai = make<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    d.check(vkAllocateCommandBuffers(d.device, &ai, &cmd), "vkAllocateCommandBuffers");
  }
  ~Impl() {
    if (queries) vkDestroyQueryPool(d.device, queries, nullptr);
    vkDestroyCommandPool(d.device, pool, nullptr);
  }

  VkCommandBuffer begin() {
    if (!recording) {
      auto bi = make<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
      bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
      d.check(vkBeginCommandBuffer(cmd, &bi), "vkBeginCommandBuffer");
      if (queries) vkCmdResetQueryPool(cmd, queries, 0, queryCapacity);
      recording = true;
    }
    return cmd;
  }

  // Every command sees the writes of the commands before it.
  void barrier() {
    auto b = make<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                      VK_ACCESS_TRANSFER_WRITE_BIT | VK_ACCESS_HOST_READ_BIT;
    const VkPipelineStageFlags stages = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    vkCmdPipelineBarrier(cmd, stages, stages | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0, nullptr, 0, nullptr);
  }

  // Records `command` between two timestamps when the commands are timed (as `name`).
  template <class Command> void timed(const char* name, Command&& command) {
    const auto slot = uint32_t(timedKernels.size());
    if (!queries || 2 * slot + 2 > queryCapacity) return command();
    timedKernels.push_back(name);
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries, 2 * slot);
    command();
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries, 2 * slot + 1);
  }

  void reserveQueries(uint32_t count) {
    if (queries) vkDestroyQueryPool(d.device, queries, nullptr);
    auto qi = make<VkQueryPoolCreateInfo>(VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO);
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = count;
    d.check(vkCreateQueryPool(d.device, &qi, nullptr, &queries), "vkCreateQueryPool");
    queryCapacity = count;
  }
};

namespace {
constexpr uint32_t kTimedDispatches = 4096;  // timestamps kept per submit
}

Commands::Commands(Device& device, bool timed) : device_(device), impl_(std::make_unique<Impl>(device.impl())) {
  if ((timed || impl_->d.profiling) && impl_->d.timestamps) impl_->reserveQueries(2 * kTimedDispatches);
}

Commands::~Commands() {
  if (impl_->recording) vkEndCommandBuffer(impl_->cmd);
}

void Commands::upload(const Buffer& to, uint64_t offset, const void* data, uint64_t bytes) {
  if (bytes == 0) return;
  Impl& c = *impl_;
  auto s = c.d.allocate(bytes, true);
  std::memcpy(s->mapped, data, bytes);
  const VkBufferCopy region{0, offset, bytes};
  const VkCommandBuffer cmd = c.begin();
  c.timed("upload", [&] { vkCmdCopyBuffer(cmd, s->buffer, to.impl().allocation->buffer, 1, &region); });
  c.uploadBytes += bytes;
  c.barrier();
  c.staging.push_back(std::move(s));
}

void Commands::download(const Buffer& from, uint64_t offset, void* data, uint64_t bytes) {
  const Region region{offset, 0, bytes};
  download(from, std::span<const Region>(&region, 1), data);
}

void Commands::download(const Buffer& from, std::span<const Region> regions, void* data) {
  Impl& c = *impl_;
  uint64_t needed = 0, lo = UINT64_MAX, hi = 0;
  for (const Region& r : regions)
    if (r.bytes) needed += r.bytes, lo = std::min(lo, r.from), hi = std::max(hi, r.from + r.bytes);
  if (needed == 0) return;
  // Regions that fill most of the range they span (rows of a window) come back in one copy of
  // that range (a GPU copies many small regions slowly: 4096 rows of 16 KiB, 13 ms against 1.3);
  // sparse ones one after the other in the staging buffer.
  const bool whole = hi - lo <= 2 * needed;
  std::vector<VkBufferCopy> copies;
  uint64_t bytes = whole ? hi - lo : 0;
  if (whole) copies.push_back({lo, 0, bytes});
  for (const Region& r : regions) {
    if (r.bytes == 0) continue;
    if (!whole) copies.push_back({r.from, bytes, r.bytes});
    c.downloads.push_back({nullptr, whole ? r.from - lo : bytes, static_cast<uint8_t*>(data) + r.to, r.bytes});
    if (!whole) bytes += r.bytes;
  }
  auto s = c.d.allocate(bytes, true);
  for (auto d = c.downloads.rbegin(); d != c.downloads.rend() && !d->from; ++d) d->from = s.get();
  const VkCommandBuffer cmd = c.begin();
  c.timed("download", [&] {
    vkCmdCopyBuffer(cmd, from.impl().allocation->buffer, s->buffer, uint32_t(copies.size()), copies.data());
  });
  c.downloadBytes += bytes;
  c.barrier();
  c.staging.push_back(std::move(s));
}

void Commands::fill(const Buffer& to, uint32_t value) {
  Impl& c = *impl_;
  vkCmdFillBuffer(c.begin(), to.impl().allocation->buffer, 0, VK_WHOLE_SIZE, value);
  c.barrier();
}

void Commands::dispatchRaw(const Kernel& kernel, const void* params, size_t paramBytes,
                           std::initializer_list<Range> bindings, uint64_t invocations) {
  Impl& c = *impl_;
  if (paramBytes != kernel.paramBytes) throw std::logic_error(std::string(kernel.name) + ": parameter block size");
  size_t descriptors = 0;
  for (uint32_t n : kernel.arrays) descriptors += n;
  if (bindings.size() != descriptors) throw std::logic_error(std::string(kernel.name) + ": binding count");
  if (invocations == 0) return;
  const Pipeline& p = c.d.pipeline(kernel);
  const VkCommandBuffer cmd = c.begin();
  std::vector<VkDescriptorBufferInfo> infos;
  infos.reserve(bindings.size());
  for (const Range& r : bindings) {
    if (r.bytes > c.d.maxRange || r.offset % 256 != 0 || r.offset + r.bytes > r.buffer->bytes())
      throw std::logic_error(std::string(kernel.name) + ": a binding exceeds the device's range limits");
    infos.push_back({r.buffer->impl().allocation->buffer, r.offset, std::max<uint64_t>(r.bytes, 4)});
  }
  std::vector<VkWriteDescriptorSet> writes(kernel.arrays.size(), make<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET));
  for (size_t i = 0, first = 0; i < writes.size(); first += kernel.arrays[i], ++i) {
    writes[i].dstBinding = uint32_t(i);
    writes[i].descriptorCount = kernel.arrays[i];
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = infos.data() + first;
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.pipeline);
  c.d.pushDescriptors(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.layout, 0, uint32_t(writes.size()), writes.data());
  if (paramBytes) vkCmdPushConstants(cmd, p.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, uint32_t(paramBytes), params);
  // Rows of at most 65535 groups, as even as possible (lavapipe splits a dispatch statically).
  const uint64_t groups = (invocations + kWorkgroupSize - 1) / kWorkgroupSize;
  const uint64_t rows = (groups + 65534) / 65535;
  if (rows > 65535) throw std::logic_error(std::string(kernel.name) + ": too many invocations");
  c.timed(kernel.name, [&] { vkCmdDispatch(cmd, uint32_t((groups + rows - 1) / rows), uint32_t(rows), 1); });
  ++c.dispatches;
  c.barrier();
}

void Commands::addToProfile(double wallSeconds) const {
  const Impl& c = *impl_;
  const std::lock_guard lock(c.d.profileMutex);
  DeviceProfile& p = c.d.profile;
  for (const auto& [name, seconds] : seconds_) {
    if (name == "upload") p.uploadSeconds += seconds;
    else if (name == "download") p.downloadSeconds += seconds;
    else p.dispatchSeconds += seconds;
  }
  p.submitSeconds += wallSeconds;
  p.uploadBytes += c.uploadBytes;
  p.downloadBytes += c.downloadBytes;
  p.dispatches += c.dispatches;
  ++p.submits;
}

void Commands::submit(const Context& ctx) {
  Impl& c = *impl_;
  Device::Impl& d = c.d;
  if (!c.recording) return;
  const auto started = std::chrono::steady_clock::now();
  c.recording = false;
  d.check(vkEndCommandBuffer(c.cmd), "vkEndCommandBuffer");
  VkFence fence = VK_NULL_HANDLE;
  auto fi = make<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  d.check(vkCreateFence(d.device, &fi, nullptr, &fence), "vkCreateFence");
  struct FenceGuard {
    VkDevice device;
    VkFence fence;
    ~FenceGuard() { vkDestroyFence(device, fence, nullptr); }
  } guard{d.device, fence};
  auto si = make<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  si.commandBufferCount = 1;
  si.pCommandBuffers = &c.cmd;
  {
    const std::lock_guard lock(d.mutex);
    d.check(vkQueueSubmit(d.queue, 1, &si, fence), "vkQueueSubmit");
  }
  bool cancelled = false;
  for (;;) {
    const VkResult r = vkWaitForFences(d.device, 1, &fence, VK_TRUE, 100'000'000);  // 0.1 s
    if (r == VK_SUCCESS) break;
    if (r != VK_TIMEOUT) d.check(r, "vkWaitForFences");
    cancelled = cancelled || ctx.cancelled();  // the device finishes what it was given first
  }
  d.instance.checkMessages();
  if (cancelled) throw Cancelled();
  for (const Impl::Download& dl : c.downloads)
    std::memcpy(dl.to, static_cast<const uint8_t*>(dl.from->mapped) + dl.offset, dl.bytes);
  seconds_.clear();
  if (!c.timedKernels.empty()) {
    std::vector<uint64_t> stamps(c.timedKernels.size() * 2);
    d.check(vkGetQueryPoolResults(d.device, c.queries, 0, uint32_t(stamps.size()), stamps.size() * 8, stamps.data(), 8,
                                  VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
            "vkGetQueryPoolResults");
    for (size_t i = 0; i < c.timedKernels.size(); ++i)
      seconds_[c.timedKernels[i]] += double(stamps[2 * i + 1] - stamps[2 * i]) * d.limits.timestampPeriod * 1e-9;
  }
  if (d.profiling) addToProfile(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  c.downloads.clear();
  for (auto& a : c.staging) d.release(std::move(a));
  c.staging.clear();
  c.timedKernels.clear();
  c.uploadBytes = c.downloadBytes = c.dispatches = 0;
  d.check(vkResetCommandBuffer(c.cmd, 0), "vkResetCommandBuffer");
}

} // namespace texfab::synthesis::vulkan
